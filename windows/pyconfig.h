/* pyconfig.h for compiling extensions of python.org's CPython 3.11 and 3.13 for Windows x64 with
 * MinGW-w64 (GCC). Written for this project: the embeddable CPython ships no headers, and every
 * header of CPython but this one is the same on every platform (the build copies them from a Linux
 * CPython of the same minor version). It states what python.org's build is: 64-bit Windows (LLP64:
 * long is 32 bits), a shared python3XY.dll the extension imports from, no debug or free-threaded
 * build. Nothing here configures CPython itself. */
#ifndef MODAL_DEFORM_WINDOWS_PYCONFIG_H
#define MODAL_DEFORM_WINDOWS_PYCONFIG_H

#if !defined(_WIN64) || !defined(__GNUC__)
#error "this pyconfig.h is for MinGW-w64 builds of extensions for 64-bit Windows CPython"
#endif

#define MS_WIN32
#define MS_WIN64
#define MS_WINDOWS
#define NT_THREADS

/* python3XY.dll: the API comes through __declspec(dllimport), PyInit_* is __declspec(dllexport). */
#define Py_ENABLE_SHARED 1
#define HAVE_DECLSPEC_DLL

/* Sizes under the Windows x64 ABI (MinGW-w64 uses the same). */
#define SIZEOF_SHORT 2
#define SIZEOF_INT 4
#define SIZEOF_LONG 4
#define SIZEOF_LONG_LONG 8
#define SIZEOF_DOUBLE 8
#define SIZEOF_FLOAT 4
#define SIZEOF_VOID_P 8
#define SIZEOF_SIZE_T 8
#define SIZEOF_TIME_T 8
#define SIZEOF_OFF_T 4
#define SIZEOF_FPOS_T 8
#define SIZEOF_WCHAR_T 2
#define SIZEOF_HKEY 8
#define SIZEOF__BOOL 1
#define ALIGNOF_SIZE_T 8
#define ALIGNOF_LONG 4
#define ALIGNOF_MAX_ALIGN_T 8

/* Py_ssize_t is the signed pointer-sized integer, as in python.org's build. */
#define HAVE_PY_SSIZE_T 1
typedef long long Py_ssize_t;

#define HAVE_LONG_LONG 1
#define PY_LONG_LONG long long
#define PYLONG_BITS_IN_DIGIT 30

#define HAVE_STDDEF_H 1
#define HAVE_STDLIB_H 1
#define HAVE_WCHAR_H 1
#define HAVE_ERRNO_H 1
#define HAVE_SYS_STAT_H 1
#define HAVE_SYS_TYPES_H 1
#define HAVE_LARGEFILE_SUPPORT

#endif
