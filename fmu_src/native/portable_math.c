/*
 * Portable sin, cos and exp: the same double operations on every platform and compiler, for the
 * builds whose C library differs from glibc (mingw-w64's sin and cos are the x87 instructions)
 * and for builds from the FMU's sources. The method is fdlibm's (Sun Microsystems, 1993: "Permission
 * to use, copy, modify, and distribute this software is freely granted, provided that this notice
 * is preserved"): Cody-Waite reduction by pi/2 in three parts, then minimax polynomials on
 * [-pi/4, pi/4] with their coefficients; written anew here. Error below 1 ULP, so they agree with
 * glibc's (correctly rounded in almost every case) except in a rare last bit; the reduction is
 * exact enough for |x| < 2^20 pi/2 (angles far beyond any swing; larger ones lose digits).
 * Compiled only with CRANE_OWN_MATH (see plant_math.h).
 */
#ifdef CRANE_OWN_MATH
#include <stdint.h>
#include <string.h>

#include "plant_math.h"

static uint64_t bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double from_bits(uint64_t u) {
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

static int exponent_of(double x) { return (int)(bits(x) >> 52 & 0x7ff); }

/* sin(x + y) for |x + y| <= pi/4, y the tail of a reduced argument (iy: y is used). */
static double kernel_sin(double x, double y, int iy) {
    static const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                        S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                        S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
    double z = x * x, v = z * x, r = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    if (!iy) return x + v * (S1 + z * r);
    return x - ((z * (0.5 * y - v * r) - y) - v * S1);
}

/* cos(x + y) for |x + y| <= pi/4. */
static double kernel_cos(double x, double y) {
    static const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                        C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                        C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
    double z = x * x, w = z * z;
    double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    double hz = 0.5 * z;
    w = 1.0 - hz;
    return w + (((1.0 - w) - hz) + (z * r - x * y));
}

/* x - n pi/2 as y[0] + y[1] with |y| <= pi/4 (about); returns n. */
static int reduce(double x, double y[2]) {
    static const double invpio2 = 6.36619772367581382433e-01, toint = 6755399441055744.0, /* 1.5 * 2^52 */
        pio2_1 = 1.57079632673412561417e+00, pio2_1t = 6.07710050650619224932e-11,
        pio2_2 = 6.07710050630396597660e-11, pio2_2t = 2.02226624879595063154e-21,
        pio2_3 = 2.02226624871116645580e-21, pio2_3t = 8.47842766036889956997e-32;
    double fn = x * invpio2 + toint - toint; /* the nearest integer */
    double r = x - fn * pio2_1, w = fn * pio2_1t, t;
    int ex = exponent_of(x);
    y[0] = r - w;
    if (ex - exponent_of(y[0]) > 16) { /* cancellation: a second round with more bits of pi/2 */
        t = r, w = fn * pio2_2, r = t - w, w = fn * pio2_2t - ((t - r) - w), y[0] = r - w;
        if (ex - exponent_of(y[0]) > 49) /* a third */
            t = r, w = fn * pio2_3, r = t - w, w = fn * pio2_3t - ((t - r) - w), y[0] = r - w;
    }
    y[1] = (r - y[0]) - w;
    return (int)(int64_t)fn;
}

static const uint64_t PIO4_BITS = 0x3fe921fb00000000u; /* about pi/4: arguments below need no reduction */
#define ABS_BITS(x) (bits(x) & 0x7fffffffffffffffu)

double crane_sin(double x) {
    uint64_t a = ABS_BITS(x);
    if (a <= PIO4_BITS + 0xffffffffu) return a < 0x3e50000000000000u ? x : kernel_sin(x, 0.0, 0); /* |x| < 2^-26 */
    if (a >= 0x7ff0000000000000u) return x - x; /* inf or nan: nan */
    double y[2];
    switch (reduce(x, y) & 3) {
    case 0: return kernel_sin(y[0], y[1], 1);
    case 1: return kernel_cos(y[0], y[1]);
    case 2: return -kernel_sin(y[0], y[1], 1);
    default: return -kernel_cos(y[0], y[1]);
    }
}

double crane_cos(double x) {
    uint64_t a = ABS_BITS(x);
    if (a <= PIO4_BITS + 0xffffffffu) return a < 0x3e40000000000000u ? 1.0 : kernel_cos(x, 0.0); /* |x| < 2^-27 */
    if (a >= 0x7ff0000000000000u) return x - x;
    double y[2];
    switch (reduce(x, y) & 3) {
    case 0: return kernel_cos(y[0], y[1]);
    case 1: return -kernel_sin(y[0], y[1], 1);
    case 2: return -kernel_cos(y[0], y[1]);
    default: return kernel_sin(y[0], y[1], 1);
    }
}

/* y 2^k, for the k of exp (-1075 < k < 1025). */
static double times_power_of_two(double y, int k) {
    if (k > 1023) return y * 2.0 * from_bits((uint64_t)(k - 1 + 1023) << 52);
    if (k < -1022) return y * from_bits((uint64_t)(k + 1000 + 1023) << 52) * from_bits((uint64_t)(1023 - 1000) << 52);
    return y * from_bits((uint64_t)(k + 1023) << 52);
}

double crane_exp(double x) {
    static const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10,
                        invln2 = 1.44269504088896338700e+00, P1 = 1.66666666666666019037e-01,
                        P2 = -2.77777777770155933842e-03, P3 = 6.61375632143793436117e-05,
                        P4 = -1.65339022054652515390e-06, P5 = 4.13813679705723846039e-08;
    if (x != x) return x;
    if (x > 709.782712893383973096) return x * 8.98846567431158e307 * 8.98846567431158e307; /* overflow: inf */
    if (x < -745.13321910194110842) return 0.0;
    double hi = x, lo = 0.0;
    int k = 0;
    double a = x < 0 ? -x : x;
    if (a > 0.5 * 0.6931471805599453) { /* x = k ln2 + r, |r| <= ln2 / 2 */
        k = a < 1.5 * 0.6931471805599453 ? (x < 0 ? -1 : 1) : (int)(invln2 * x + (x < 0 ? -0.5 : 0.5));
        hi = x - k * ln2_hi, lo = k * ln2_lo, x = hi - lo;
    } else if (a < 3.725290298461914e-09) { /* 2^-28 */
        return 1.0 + x;
    }
    double xx = x * x, c = x - xx * (P1 + xx * (P2 + xx * (P3 + xx * (P4 + xx * P5))));
    double y = 1.0 + (x * c / (2.0 - c) - lo + hi);
    return k == 0 ? y : times_power_of_two(y, k);
}
#else
typedef int portable_math_unused; /* an empty translation unit is not ISO C */
#endif
