/* For the Windows test Pythons under Wine only (windows/windows.mk); never shipped, never loaded on
 * Windows. Wine 8.0's ucrtbase.dll exports the UCRT's C99 complex functions (crealf, cexpf, cabs,
 * cpow, _Cmulcc, ...) as stubs that abort the process when called. NumPy 2's and SciPy's Windows
 * wheels call them, so `import numpy` (2.2 and later) or `import scipy` aborts under Wine, where on
 * Windows they work. A .pth file in each test environment loads this DLL at start-up; it writes a
 * jump to its own implementation over each export of ucrtbase.dll that is such a stub, and leaves
 * alone every export Wine implements.
 *
 * Why not a stand-in DLL chosen by WINEDLLOVERRIDES: Wine 8.0 resolves the API sets the wheels
 * import (api-ms-win-crt-math-l1-1-0.dll) through its API set schema straight to its builtin
 * ucrtbase.dll, before any override is read; and a native ucrtbase.dll forwarding to a renamed copy
 * of Wine's leaves CPython without its standard streams.
 *
 * The implementations are MinGW-w64's C99 complex functions (libmingwex). The UCRT's complex types
 * are structs (_Fcomplex, _Dcomplex, _Lcomplex of the Windows SDK's complex.h), passed and returned
 * as MSVC passes structs; its long double is double, so each "l" function is its "d" function. */
#include <complex.h>
#include <math.h>
#include <string.h>
#include <windows.h>

typedef struct {
  float part[2];
} FloatComplex; /* _Fcomplex */
typedef struct {
  double part[2];
} DoubleComplex; /* _Dcomplex and _Lcomplex */

static float _Complex from_float(FloatComplex z) { return __builtin_complex(z.part[0], z.part[1]); }
static double _Complex from_double(DoubleComplex z) {
  return __builtin_complex(z.part[0], z.part[1]);
}
static FloatComplex to_float(float _Complex z) { return (FloatComplex){{crealf(z), cimagf(z)}}; }
static DoubleComplex to_double(double _Complex z) { return (DoubleComplex){{creal(z), cimag(z)}}; }

/* clog10 and norm are Microsoft's additions to C99's set: the base-10 logarithm and |z|^2. */
static double _Complex clog10_of(double _Complex z) { return clog(z) / M_LN10; }
static float _Complex clog10f_of(float _Complex z) { return clogf(z) / (float)M_LN10; }
static double norm_of(double _Complex z) { return creal(z) * creal(z) + cimag(z) * cimag(z); }
static float normf_of(float _Complex z) { return crealf(z) * crealf(z) + cimagf(z) * cimagf(z); }

/* ucrt_NAME (double) and ucrt_NAMEf (float) from the C99 functions of each precision. */
#define COMPLEX_TO_COMPLEX(name, double_fn, float_fn) \
  static DoubleComplex ucrt_##name(DoubleComplex z) { \
    return to_double(double_fn(from_double(z)));      \
  }                                                   \
  static FloatComplex ucrt_##name##f(FloatComplex z) { return to_float(float_fn(from_float(z))); }
#define COMPLEX_TO_REAL(name, double_fn, float_fn)                                 \
  static double ucrt_##name(DoubleComplex z) { return double_fn(from_double(z)); } \
  static float ucrt_##name##f(FloatComplex z) { return float_fn(from_float(z)); }

COMPLEX_TO_COMPLEX(cacos, cacos, cacosf)
COMPLEX_TO_COMPLEX(cacosh, cacosh, cacoshf)
COMPLEX_TO_COMPLEX(casin, casin, casinf)
COMPLEX_TO_COMPLEX(casinh, casinh, casinhf)
COMPLEX_TO_COMPLEX(catan, catan, catanf)
COMPLEX_TO_COMPLEX(catanh, catanh, catanhf)
COMPLEX_TO_COMPLEX(ccos, ccos, ccosf)
COMPLEX_TO_COMPLEX(ccosh, ccosh, ccoshf)
COMPLEX_TO_COMPLEX(cexp, cexp, cexpf)
COMPLEX_TO_COMPLEX(clog, clog, clogf)
COMPLEX_TO_COMPLEX(clog10, clog10_of, clog10f_of)
COMPLEX_TO_COMPLEX(conj, conj, conjf)
COMPLEX_TO_COMPLEX(cproj, cproj, cprojf)
COMPLEX_TO_COMPLEX(csin, csin, csinf)
COMPLEX_TO_COMPLEX(csinh, csinh, csinhf)
COMPLEX_TO_COMPLEX(csqrt, csqrt, csqrtf)
COMPLEX_TO_COMPLEX(ctan, ctan, ctanf)
COMPLEX_TO_COMPLEX(ctanh, ctanh, ctanhf)
COMPLEX_TO_REAL(cabs, cabs, cabsf)
COMPLEX_TO_REAL(carg, carg, cargf)
COMPLEX_TO_REAL(cimag, cimag, cimagf)
COMPLEX_TO_REAL(creal, creal, crealf)
COMPLEX_TO_REAL(norm, norm_of, normf_of)

static DoubleComplex ucrt_cpow(DoubleComplex x, DoubleComplex y) {
  return to_double(cpow(from_double(x), from_double(y)));
}
static FloatComplex ucrt_cpowf(FloatComplex x, FloatComplex y) {
  return to_float(cpowf(from_float(x), from_float(y)));
}
/* _Cbuild makes re + i im; _Cmulcc multiplies two complex numbers, _Cmulcr one by a real. */
static DoubleComplex ucrt_Cbuild(double re, double im) { return (DoubleComplex){{re, im}}; }
static FloatComplex ucrt_FCbuild(float re, float im) { return (FloatComplex){{re, im}}; }
static DoubleComplex ucrt_Cmulcc(DoubleComplex x, DoubleComplex y) {
  return to_double(from_double(x) * from_double(y));
}
static FloatComplex ucrt_FCmulcc(FloatComplex x, FloatComplex y) {
  return to_float(from_float(x) * from_float(y));
}
static DoubleComplex ucrt_Cmulcr(DoubleComplex x, double y) {
  return (DoubleComplex){{x.part[0] * y, x.part[1] * y}};
}
static FloatComplex ucrt_FCmulcr(FloatComplex x, float y) {
  return (FloatComplex){{x.part[0] * y, x.part[1] * y}};
}

#define DFL(name) \
  {#name, (void*)ucrt_##name}, {#name "f", (void*)ucrt_##name##f}, { #name "l", (void*)ucrt_##name }
static const struct {
  const char* name;
  void* implementation;
} kFunctions[] = {
    DFL(cacos),
    DFL(cacosh),
    DFL(casin),
    DFL(casinh),
    DFL(catan),
    DFL(catanh),
    DFL(ccos),
    DFL(ccosh),
    DFL(cexp),
    DFL(clog),
    DFL(clog10),
    DFL(conj),
    DFL(cproj),
    DFL(csin),
    DFL(csinh),
    DFL(csqrt),
    DFL(ctan),
    DFL(ctanh),
    DFL(cabs),
    DFL(carg),
    DFL(cimag),
    DFL(creal),
    DFL(norm),
    DFL(cpow),
    {"_Cbuild", (void*)ucrt_Cbuild},
    {"_FCbuild", (void*)ucrt_FCbuild},
    {"_LCbuild", (void*)ucrt_Cbuild},
    {"_Cmulcc", (void*)ucrt_Cmulcc},
    {"_FCmulcc", (void*)ucrt_FCmulcc},
    {"_LCmulcc", (void*)ucrt_Cmulcc},
    {"_Cmulcr", (void*)ucrt_Cmulcr},
    {"_FCmulcr", (void*)ucrt_FCmulcr},
    {"_LCmulcr", (void*)ucrt_Cmulcr},
};

/* A Wine stub, as winebuild writes it: sub $0x28,%rsp; lea dll(%rip),%rcx; lea name(%rip),%rdx;
 * call __wine_spec_unimplemented_stub (23 bytes). */
static int is_wine_stub(const unsigned char* code) {
  return memcmp(code, "\x48\x83\xec\x28\x48\x8d\x0d", 7) == 0 &&
         memcmp(code + 11, "\x48\x8d\x15", 3) == 0 && code[18] == 0xe8;
}

/* movabs $target,%rax; jmp *%rax (12 bytes, within the stub; %rax is free at a call's entry). */
static void jump(unsigned char* code, void* target) {
  DWORD protection;
  VirtualProtect(code, 12, PAGE_EXECUTE_READWRITE, &protection);
  code[0] = 0x48;
  code[1] = 0xb8;
  memcpy(code + 2, &target, sizeof target);
  code[10] = 0xff;
  code[11] = 0xe0;
  VirtualProtect(code, 12, protection, &protection);
  FlushInstructionCache(GetCurrentProcess(), code, 12);
}

BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID reserved) {
  (void)instance;
  (void)reserved;
  if (reason != DLL_PROCESS_ATTACH) return TRUE;
  HMODULE ucrtbase = LoadLibraryA("ucrtbase.dll");
  if (!ucrtbase) return FALSE;
  for (size_t i = 0; i < sizeof kFunctions / sizeof kFunctions[0]; ++i) {
    unsigned char* code = (unsigned char*)GetProcAddress(ucrtbase, kFunctions[i].name);
    if (code && is_wine_stub(code)) jump(code, kFunctions[i].implementation);
  }
  return TRUE;
}
