/* GKlib's gk_arch.h includes <sys/resource.h> on every compiler but MSVC; MinGW-w64 has none.
 * With WIN32 defined GKlib uses nothing from it (timers.c takes clock() instead of getrusage). */
