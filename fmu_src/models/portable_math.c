/*
 * Portable sin, cos, exp, tanh, log, atan and atan2: the same double operations on every platform and compiler, for
 * the builds whose C library differs from glibc (mingw-w64's sin and cos are the x87 instructions) and
 * for builds from the FMU's sources. The method is fdlibm's (Sun Microsystems, 1993: "Permission to use,
 * copy, modify, and distribute this software is freely granted, provided that this notice is
 * preserved"): for sin and cos Cody-Waite reduction by pi/2 in three parts, then minimax polynomials on
 * [-pi/4, pi/4]; for exp, expm1 (under tanh) and log a reduction by ln2 or to [sqrt(2)/2, sqrt(2)], then
 * their rational or polynomial forms; for atan a reduction around atan(1/2), atan(1), atan(3/2), atan(inf) and an
 * odd polynomial, atan2 from it by quadrant; with fdlibm's coefficients, written anew here. Errors below 1 ULP
 * (tanh: below 3 ULP of glibc's), so they agree with glibc's except in a rare last bit; the reduction of
 * sin and cos is exact enough for |x| < 2^20 pi/2 (angles far beyond any swing; larger ones lose digits).
 * Compiled only with CRANE_OWN_MATH (see plant_math.h).
 */
#ifdef CRANE_OWN_MATH
#include <math.h> /* INFINITY only */
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

/* x with its high 32 bits replaced by `high` and its low ones kept. */
static double with_high_word(double x, uint32_t high) {
    return from_bits((bits(x) & 0xffffffffu) | (uint64_t)high << 32);
}

/* y 2^k by adding k to the exponent (y normal and the result too, as in expm1's reconstruction). */
static double add_exponent(double y, int k) { return from_bits((uint64_t)((int64_t)bits(y) + ((int64_t)k << 52))); }

/* exp(x) - 1, fdlibm's method: x = k ln2 + r with r's rounding error c, then a rational form in r. */
static double expm1_(double x) {
    static const double o_threshold = 7.09782712893383973096e+02, ln2_hi = 6.93147180369123816490e-01,
                        ln2_lo = 1.90821492927058770002e-10, invln2 = 1.44269504088896338700e+00,
                        Q1 = -3.33333333333331316428e-02, Q2 = 1.58730158725481460165e-03,
                        Q3 = -7.93650757867487942473e-05, Q4 = 4.00821782732936239552e-06,
                        Q5 = -2.01099218183624371326e-07;
    uint32_t hx = (uint32_t)(bits(x) >> 32) & 0x7fffffffu;
    int negative = x < 0, k = 0;
    double hi, lo, c = 0.0;
    if (hx >= 0x4043687Au) { /* |x| >= 56 ln2 */
        if (x != x) return x;
        if (hx >= 0x7ff00000u) return negative ? -1.0 : x;
        if (x > o_threshold) return x * 8.98846567431158e307 * 8.98846567431158e307; /* overflow: inf */
        if (negative) return -1.0;
    }
    if (hx > 0x3fd62e42u) { /* |x| > ln2 / 2 */
        if (hx < 0x3FF0A2B2u) { /* |x| < 1.5 ln2 */
            hi = negative ? x + ln2_hi : x - ln2_hi, lo = negative ? -ln2_lo : ln2_lo, k = negative ? -1 : 1;
        } else {
            k = (int)(invln2 * x + (negative ? -0.5 : 0.5));
            double t = k;
            hi = x - t * ln2_hi, lo = t * ln2_lo;
        }
        x = hi - lo, c = (hi - x) - lo;
    } else if (hx < 0x3c900000u) { /* |x| < 2^-54 */
        return x;
    }
    double hfx = 0.5 * x, hxs = x * hfx;
    double r1 = 1.0 + hxs * (Q1 + hxs * (Q2 + hxs * (Q3 + hxs * (Q4 + hxs * Q5))));
    double t = 3.0 - r1 * hfx, e = hxs * ((r1 - t) / (6.0 - x * t));
    if (k == 0) return x - (x * e - hxs);
    e = x * (e - c) - c;
    e -= hxs;
    if (k == -1) return 0.5 * (x - e) - 0.5;
    if (k == 1) return x < -0.25 ? -2.0 * (e - (x + 0.5)) : 1.0 + 2.0 * (x - e);
    if (k <= -2 || k > 56) return add_exponent(1.0 - (e - x), k) - 1.0;
    if (k < 20) return add_exponent(with_high_word(1.0, 0x3ff00000u - (0x200000u >> k)) - (e - x), k); /* 1 - 2^-k */
    return add_exponent(x - (e + with_high_word(1.0, (uint32_t)(0x3ff - k) << 20)) + 1.0, k);          /* 2^-k */
}

double crane_tanh(double x) {
    uint32_t ix = (uint32_t)(bits(x) >> 32) & 0x7fffffffu;
    double z;
    if (ix >= 0x7ff00000u) return x != x ? x : x > 0 ? 1.0 : -1.0;
    if (ix < 0x3c800000u) return x * (1.0 + x); /* |x| < 2^-55 */
    double a = x < 0 ? -x : x;
    if (ix >= 0x40360000u) z = 1.0; /* |x| >= 22 */
    else if (ix >= 0x3ff00000u) z = 1.0 - 2.0 / (expm1_(2.0 * a) + 2.0); /* |x| >= 1 */
    else {
        double t = expm1_(-2.0 * a);
        z = -t / (t + 2.0);
    }
    return x < 0 ? -z : z;
}

/* log(x), fdlibm's method: x = 2^k (1 + f) with sqrt(2)/2 < 1 + f < sqrt(2), s = f / (2 + f), a polynomial in s^2. */
double crane_log(double x) {
    static const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10,
                        two54 = 1.80143985094819840000e+16, Lg1 = 6.666666666666735130e-01,
                        Lg2 = 3.999999999940941908e-01, Lg3 = 2.857142874366239149e-01,
                        Lg4 = 2.222219843214978396e-01, Lg5 = 1.818357216161805012e-01,
                        Lg6 = 1.531383769920937332e-01, Lg7 = 1.479819860511658591e-01;
    if (x != x || x == INFINITY) return x + x;
    if (x < 0) return (x - x) / 0.0; /* nan */
    if (x == 0) return -INFINITY;
    int k = 0;
    int32_t hx = (int32_t)(bits(x) >> 32);
    if (hx < 0x00100000) { /* subnormal: scale up */
        k -= 54, x *= two54;
        hx = (int32_t)(bits(x) >> 32);
    }
    k += (hx >> 20) - 1023;
    hx &= 0x000fffff;
    int32_t i = (hx + 0x95f64) & 0x100000;
    x = with_high_word(x, (uint32_t)(hx | (i ^ 0x3ff00000))); /* x or x / 2: within [sqrt(2)/2, sqrt(2)] */
    k += i >> 20;
    double f = x - 1.0, dk = k;
    if ((0x000fffff & (2 + hx)) < 3) { /* |f| < 2^-20 */
        if (f == 0) return k == 0 ? 0.0 : dk * ln2_hi + dk * ln2_lo;
        double R = f * f * (0.5 - 0.33333333333333333 * f);
        return k == 0 ? f - R : dk * ln2_hi - ((R - dk * ln2_lo) - f);
    }
    double s = f / (2.0 + f), z = s * s, w = z * z;
    double t1 = w * (Lg2 + w * (Lg4 + w * Lg6)), t2 = z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7))), R = t2 + t1;
    if (((hx - 0x6147a) | (0x6b851 - hx)) > 0) {
        double hfsq = 0.5 * f * f;
        return k == 0 ? f - (hfsq - s * (hfsq + R)) : dk * ln2_hi - ((hfsq - (s * (hfsq + R) + dk * ln2_lo)) - f);
    }
    return k == 0 ? f - s * (f - R) : dk * ln2_hi - ((s * (f - R) - dk * ln2_lo) - f);
}

/* atan(x): fdlibm's method, x reduced to |x| < 7/16 around one of atan(1/2), atan(1), atan(3/2), atan(inf), then an
   odd polynomial in x (coefficients as fdlibm's). */
double crane_atan(double x) {
    static const double atanhi[] = {4.63647609000806093515e-01, 7.85398163397448278999e-01,
                                    9.82793723247329054082e-01, 1.57079632679489655800e+00};
    static const double atanlo[] = {2.26987774529616870924e-17, 3.06161699786838301793e-17,
                                    1.39033110312309984516e-17, 6.12323399573676603587e-17};
    static const double aT[] = {3.33333333333329318027e-01,  -1.99999999998764832476e-01, 1.42857142725034663711e-01,
                                -1.11111104054623557880e-01, 9.09088713343650656196e-02,  -7.69187620504482999495e-02,
                                6.66107313738753120669e-02,  -5.83357013379057348645e-02, 4.97687799461593236017e-02,
                                -3.65315727442169155270e-02, 1.62858201153657823623e-02};
    uint32_t hx = (uint32_t)(bits(x) >> 32), ix = hx & 0x7fffffffu;
    int id;
    if (ix >= 0x44100000u) { /* |x| >= 2^66 */
        if (x != x) return x + x;
        return (hx >> 31) ? -atanhi[3] - atanlo[3] : atanhi[3] + atanlo[3];
    }
    if (ix < 0x3fdc0000u) {                     /* |x| < 7/16 */
        if (ix < 0x3e400000u) return x;         /* |x| < 2^-27 */
        id = -1;
    } else {
        x = x < 0 ? -x : x;
        if (ix < 0x3ff30000u) {                 /* |x| < 19/16 */
            if (ix < 0x3fe60000u) {             /* 7/16 <= |x| < 11/16 */
                id = 0, x = (2.0 * x - 1.0) / (2.0 + x);
            } else {                            /* 11/16 <= |x| < 19/16 */
                id = 1, x = (x - 1.0) / (x + 1.0);
            }
        } else if (ix < 0x40038000u) {          /* |x| < 39/16 */
            id = 2, x = (x - 1.5) / (1.0 + 1.5 * x);
        } else {                                /* 39/16 <= |x| < 2^66 */
            id = 3, x = -1.0 / x;
        }
    }
    double z = x * x, w = z * z;
    double s1 = z * (aT[0] + w * (aT[2] + w * (aT[4] + w * (aT[6] + w * (aT[8] + w * aT[10])))));
    double s2 = w * (aT[1] + w * (aT[3] + w * (aT[5] + w * (aT[7] + w * aT[9]))));
    if (id < 0) return x - x * (s1 + s2);
    z = atanhi[id] - ((x * (s1 + s2) - atanlo[id]) - x);
    return (hx >> 31) ? -z : z;
}

/* atan2(y, x): fdlibm's, on crane_atan(|y / x|) with the quadrant's pi and its tail. */
double crane_atan2(double y, double x) {
    static const double pi_o_4 = 7.8539816339744827900e-01, pi_o_2 = 1.5707963267948965580e+00,
                        pi = 3.1415926535897931160e+00, pi_lo = 1.2246467991473531772e-16;
    if (x != x || y != y) return x + y;
    if (x == 1.0) return crane_atan(y);
    int m = (int)(bits(y) >> 63) | (int)(bits(x) >> 63) << 1; /* 2 sign(x) + sign(y) */
    if (y == 0) return m == 0 || m == 1 ? y : m == 2 ? pi : -pi;
    if (x == 0) return m & 1 ? -pi_o_2 : pi_o_2;
    if (x == INFINITY || x == -INFINITY) {
        if (y == INFINITY || y == -INFINITY) {
            static const double both[] = {pi_o_4, -pi_o_4, 3.0 * pi_o_4, -3.0 * pi_o_4};
            return both[m];
        }
        return m == 0 ? 0.0 : m == 1 ? -0.0 : m == 2 ? pi : -pi;
    }
    if (y == INFINITY || y == -INFINITY) return m & 1 ? -pi_o_2 : pi_o_2;
    int k = exponent_of(y) - exponent_of(x);
    double z;
    if (k > 60) z = pi_o_2 + 0.5 * pi_lo;    /* |y / x| > 2^60 */
    else if (m & 2 && k < -60) z = 0.0;       /* |y| / x < -2^60 */
    else z = crane_atan(y / x < 0 ? -(y / x) : y / x);
    switch (m) {
    case 0: return z;
    case 1: return -z;
    case 2: return pi - (z - pi_lo);
    default: return (z - pi_lo) - pi;
    }
}
#else
typedef int portable_math_unused; /* an empty translation unit is not ISO C */
#endif
