/*
 * The elementary functions the plant uses. By default the C library's: on Linux that is glibc's
 * libm, the one CPython uses, so the native plant gives the Python plant's numbers. mingw-w64's
 * libm differs (its sin and cos are the x87 instructions, up to 153 ULP off), so the Windows build
 * defines CRANE_OWN_MATH and takes portable_math.c, the same source on every platform.
 */
#ifndef PLANT_MATH_H
#define PLANT_MATH_H

#ifdef CRANE_OWN_MATH
double crane_sin(double x);
double crane_cos(double x);
double crane_exp(double x);
double crane_tanh(double x);
double crane_log(double x);
double crane_atan(double x);
double crane_atan2(double y, double x);
#define SIN crane_sin
#define COS crane_cos
#define EXP crane_exp
#define TANH crane_tanh
#define LOG crane_log
#define ATAN2 crane_atan2
#else
#include <math.h>
#define SIN sin
#define COS cos
#define EXP exp
#define TANH tanh
#define LOG log
#define ATAN2 atan2
#endif

/* Python's x ** 2: the C library's pow(x, 2.0), which glibc's does not always round as x * x, kept from being
   folded into x * x by the compiler; the portable math's is x * x. */
#ifdef CRANE_OWN_MATH
static inline double square(double x) { return x * x; }
#else
static inline double square(double x) {
    volatile double two = 2.0;
    return pow(x, two);
}
#endif

/* What Python raises where x ** 2 of a finite x overflows (square() then gives inf). */
#define SQUARE_OVERFLOW "OverflowError: (34, 'Numerical result out of range')"

#endif
