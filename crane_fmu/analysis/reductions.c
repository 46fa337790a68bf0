/*
 * numpy's reductions of the run metrics (crane_fmu/analysis/metrics.py) in C, for the batch path
 * (fast_metrics.py loads it through crane_fmu/cosim/compiled_loop.py's compiler): the same arithmetic
 * in the same order, so the same bits, and no temporary arrays. A column is `v[i * stride]` (a column
 * of a block of rows); each column has its own stride. Compiled with -ffp-contract=off: no fused
 * multiply-add where numpy has none.
 */
#include <math.h>

/* np.max over v[from:to] (from < to) of np.abs(v - offset) (`absolute`), else of sign * (v - offset): so
   np.max(np.abs(v)), np.max(x), -np.min(x) (sign -1), np.max(direction * (x - x_d)). NaN when one is NaN (numpy's
   maximum propagates it). The operations are numpy's, each exact for offset 0 and sign 1. */
double extreme(const double *v, long stride, long from, long to, double sign, double offset, int absolute) {
    double m = absolute ? fabs(v[from * stride] - offset) : sign * (v[from * stride] - offset);
    if (m != m) return m;
    if (absolute)
        for (long i = from + 1; i < to; i++) {
            double a = fabs(v[i * stride] - offset);
            if (a > m) m = a;
            else if (a != a) return a;
        }
    else
        for (long i = from + 1; i < to; i++) {
            double a = sign * (v[i * stride] - offset);
            if (a > m) m = a;
            else if (a != a) return a;
        }
    return m;
}

/* The first i with t[i] >= threshold (n: none), by bisection: t is a run's time grid, never decreasing, so numpy's
   mask `t >= threshold` is the points from there on. */
long first_at_least(const double *t, long stride, long n, double threshold) {
    long lo = 0, hi = n;
    while (lo < hi) {
        long mid = lo + (hi - lo) / 2;
        if (t[mid * stride] >= threshold) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* settling_time's last point outside the band: the largest i where some signal s_j = (v_j - offset_j) / divisor_j
   * factor_j has not |s_j| <= band (NaN is outside); -1 when there is none; -2: more than 8 signals. The operations
   are numpy's `x - x_d` and `theta / angle_band * position_band`, each exact for offset 0, divisor 1, factor 1. */
long last_outside(const double *const v[], const long stride[], long count, const double offset[],
                  const double divisor[], const double factor[], long n, double band) {
    int plain[8]; /* a signal whose operations each give it back: offset 0, divisor 1, factor 1 */
    if (count > 8) return -2;
    for (long j = 0; j < count; j++) plain[j] = offset[j] == 0. && divisor[j] == 1. && factor[j] == 1.;
    for (long i = n - 1; i >= 0; i--)
        for (long j = 0; j < count; j++) {
            double s = v[j][i * stride[j]];
            if (!plain[j]) s = (s - offset[j]) / divisor[j] * factor[j];
            if (!(fabs(s) <= band)) return i;
        }
    return -1;
}

/* numpy's pairwise summation of a contiguous array (numpy/_core/src/umath/loops_utils.h.src, pairwise_sum): a
   plain sum under 8 values, eight accumulators up to 128, else two halves (the first a multiple of 8). */
static double pairwise(const double *a, long n) {
    if (n < 8) {
        double res = 0.;
        for (long i = 0; i < n; i++) res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8];
        long i;
        for (int j = 0; j < 8; j++) r[j] = a[j];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++) r[j] += a[i + j];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++) res += a[i];
        return res;
    }
    long n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise(a, n2) + pairwise(a + n2, n - n2);
}

enum { SQUARES, EFFORT, TRAPEZOID, VARIATION, TRAPEZOID_OF };

/*
 * np.sum of the terms of one metric, made in `terms` (room for n): numpy's add.reduce starts from its identity, 0,
 * and adds the pairwise sum of the terms.
 *   SQUARES    np.square(a)                                                  (rms: np.mean is this sum / n)
 *   EFFORT     np.square(a[:-1]) * np.diff(t)                                (move_metrics' effort)
 *   TRAPEZOID  (y[1:] + y[:-1]) * np.diff(t), y = np.square(a) + np.square(b)  (_trapezoid of the swing)
 *   VARIATION  np.abs(np.diff(a))                                            (u_total_variation)
 *   TRAPEZOID_OF (a[1:] + a[:-1]) * np.diff(t)                               (_trapezoid of squares made by numpy)
 */
double sum_of(int kind, const double *a, long sa, const double *b, long sb, const double *t, long st, long n,
              double *terms) {
    long m = kind == SQUARES ? n : n - 1;
    for (long i = 0; i < m; i++) {
        double x = a[i * sa];
        switch (kind) {
        case SQUARES:
            terms[i] = x * x;
            break;
        case EFFORT:
            terms[i] = x * x * (t[(i + 1) * st] - t[i * st]);
            break;
        case TRAPEZOID: {
            double next = a[(i + 1) * sa];
            double y0 = x * x + b[i * sb] * b[i * sb], y1 = next * next + b[(i + 1) * sb] * b[(i + 1) * sb];
            terms[i] = (y1 + y0) * (t[(i + 1) * st] - t[i * st]);
            break;
        }
        case VARIATION:
            terms[i] = fabs(a[(i + 1) * sa] - x);
            break;
        default:
            terms[i] = (a[(i + 1) * sa] + x) * (t[(i + 1) * st] - t[i * st]);
        }
    }
    return 0. + (m > 0 ? pairwise(terms, m) : 0.);
}
