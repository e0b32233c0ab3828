// <windows.h> on Windows, without its min and max macros (they break std::min and std::max);
// nothing elsewhere.
#pragma once

#ifdef _WIN32
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>
#endif
