/*
 * crane_fmu/model/qp.py in C, function for function; see qp.h. Python's sum orders are kept: reduce(add, ...)
 * and total() add left to right from 0.0, accumulate() adds each term to the sum before it.
 */
#include <math.h>
#include <string.h>

#include "qp.h"

#define FEASIBLE 1e-9  /* qp.FEASIBLE */
#define PARALLEL 1e-12 /* qp.PARALLEL */

int qp_cholesky(const double *a, int n, double *factor) {
    memset(factor, 0, (size_t)n * (size_t)n * sizeof *factor);
    for (int i = 0; i < n; i++) {
        double *row = factor + (size_t)i * n;
        for (int j = 0; j <= i; j++) {
            const double *other = factor + (size_t)j * n;
            double acc = a[(size_t)i * n + j];
            for (int k = 0; k < j; k++) acc -= row[k] * other[k];
            if (i == j) {
                if (!(acc > 0.0)) return -1;
                row[i] = sqrt(acc);
            } else {
                row[j] = acc / other[j];
            }
        }
    }
    return 0;
}

/* qp.inverse_spd(): a^-1 = L^-T L^-1; scratch: 2 n^2 doubles. */
static int inverse_spd(const double *a, int n, double *result, double *scratch) {
    double *factor = scratch, *linv = scratch + (size_t)n * n;
    if (qp_cholesky(a, n, factor)) return -1;
    memset(linv, 0, (size_t)n * (size_t)n * sizeof *linv);
    for (int j = 0; j < n; j++) {
        linv[(size_t)j * n + j] = 1.0 / factor[(size_t)j * n + j];
        for (int i = j + 1; i < n; i++) {
            double acc = 0.0;
            for (int k = j; k < i; k++) acc -= factor[(size_t)i * n + k] * linv[(size_t)k * n + j];
            linv[(size_t)i * n + j] = acc / factor[(size_t)i * n + i];
        }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j <= i; j++) {
            double acc = 0.0;
            for (int k = i; k < n; k++) acc += linv[(size_t)k * n + i] * linv[(size_t)k * n + j];
            result[(size_t)i * n + j] = result[(size_t)j * n + i] = acc;
        }
    return 0;
}

/* qp.span_dot(): r' x for row i, added left to right from 0.0. */
static double span_dot(const QpPrepared *p, int i, const double *x) {
    const double *values = p->values + p->offset[i], *at = x + p->first[i];
    double acc = 0.0;
    for (int k = 0; k < p->length[i]; k++) acc += values[k] * at[k];
    return acc;
}

/* qp.chains(): whether row i is row i - 1 plus one more element. */
static int extends(const QpPrepared *p, int i) {
    if (p->first[i] != p->first[i - 1] || p->length[i] != p->length[i - 1] + 1) return 0;
    const double *a = p->values + p->offset[i], *b = p->values + p->offset[i - 1];
    for (int k = 0; k < p->length[i - 1]; k++)
        if (!(a[k] == b[k])) return 0;
    return 1;
}

/* qp.row_products(): r' x for every row, one pass per chain. */
static void row_products(const QpPrepared *p, const double *x, double *out) {
    for (int begin = 0; begin < p->m; begin = p->chain_end[begin] + 1) {
        int end = p->chain_end[begin];
        out[begin] = span_dot(p, begin, x);
        const double *tail = p->values + p->offset[end]; /* the chain's last row holds every element */
        int first = p->first[begin];
        for (int i = begin + 1; i <= end; i++) {
            int k = p->length[i] - 1;
            out[i] = out[i - 1] + tail[k] * x[first + k];
        }
    }
}

int qp_prepare(QpPrepared *p, const double *h, double *scratch) {
    int n = p->n, m = p->m;
    if (inverse_spd(h, n, p->hinv, scratch)) return -1;
    for (int begin = 0, i = 1; i <= m; i++) {
        p->chain_end[i - 1] = -1;
        if (i == m || !extends(p, i)) p->chain_end[begin] = i - 1, begin = i;
    }
    for (int i = 0; i < m; i++) {
        for (int j = 0; j < n; j++) p->g[(size_t)i * n + j] = span_dot(p, i, p->hinv + (size_t)j * n);
        double norm = 0.0;
        for (int k = 0; k < p->length[i]; k++) norm += fabs(p->values[p->offset[i] + k]);
        p->norms[i] = norm;
    }
    return 0;
}

/* The packed Cholesky factor's row i (i + 1 values). */
#define ROW(factor, i) ((factor) + (size_t)(i) * ((i) + 1) / 2)

void qp_cholesky_solve(const double *packed, int m, const double *rhs, double *scratch, double *y) {
    double *forward = scratch;
    for (int i = 0; i < m; i++) {
        const double *row = ROW(packed, i);
        double acc = rhs[i];
        for (int k = 0; k < i; k++) acc -= row[k] * forward[k];
        forward[i] = acc / row[i];
    }
    for (int i = m - 1; i >= 0; i--) {
        double acc = forward[i];
        for (int k = i + 1; k < m; k++) acc -= ROW(packed, k)[i] * y[k];
        y[i] = acc / ROW(packed, i)[i];
    }
}

/* The working set: its rows, their sides, whether a row is in it, the packed factor of S_W, and S's row
   scratch. */
typedef struct {
    int *rows, *sides, *held, size;
    double *factor, *column;
} Working;

/* qp._append(): grow the factor of S_W by `row`; 0 (nothing changed) when the row depends on W. S's row is
   qp.prepare's row_products of G's row. */
static int append(const QpPrepared *p, Working *w, int row, int side) {
    double *column = w->column, *fresh = ROW(w->factor, w->size);
    row_products(p, p->g + (size_t)row * p->n, column);
    for (int i = 0; i < w->size; i++) {
        const double *other = ROW(w->factor, i);
        double acc = column[w->rows[i]];
        for (int k = 0; k < i; k++) acc -= fresh[k] * other[k];
        fresh[i] = acc / other[i];
    }
    double acc = column[row];
    for (int k = 0; k < w->size; k++) acc -= fresh[k] * fresh[k];
    if (!(acc > 1e-12 * column[row])) return 0;
    fresh[w->size] = sqrt(acc);
    w->rows[w->size] = row, w->sides[w->size] = side, w->held[row] = 1, w->size++;
    return 1;
}

static double bound(const double *lower, const double *upper, int row, int side) {
    return side > 0 ? upper[row] : lower[row];
}

void qp_solve(const QpPrepared *p, const double *f, const double *lower, const double *upper, const double *start,
              const int *hint_rows, const int *hint_sides, int n_hint, int max_iterations, double *work, int *iwork,
              QpSolution *out) {
    int n = p->n, m = p->m;
    double *x = out->x, *xu = work, *target = xu + n, *step = target + n, *scratch = step + n;
    double *rx = scratch + m, *rxu = rx + m, *rp = rxu + m, *lam = rp + m, *rhs = lam + m, *column = rhs + m;
    Working w = {iwork, iwork + m, iwork + 2 * m, 0, column + m, column};
    memset(w.held, 0, (size_t)m * sizeof *w.held);
    memcpy(x, start, (size_t)n * sizeof *x);
    for (int i = 0; i < n; i++) {
        const double *hrow = p->hinv + (size_t)i * n;
        double acc = 0.0;
        for (int j = 0; j < n; j++) acc += hrow[j] * f[j];
        xu[i] = -acc; /* the unconstrained minimiser -H^-1 f */
    }
    row_products(p, x, rx);
    int have_rxu = 0;
    for (int i = 0; i < n_hint; i++) {
        int row = hint_rows[i], side = hint_sides[i];
        double b = bound(lower, upper, row, side);
        if (fabs(rx[row] - b) <= FEASIBLE * (1.0 + fabs(b)) && !w.held[row]) append(p, &w, row, side);
    }
    int iterations = 0;
    while (iterations < max_iterations) {
        iterations++;
        /* the minimiser on the working set, and its multipliers */
        memcpy(target, xu, (size_t)n * sizeof *target);
        if (w.size) {
            if (!have_rxu) row_products(p, xu, rxu), have_rxu = 1;
            for (int i = 0; i < w.size; i++) rhs[i] = rxu[w.rows[i]] - bound(lower, upper, w.rows[i], w.sides[i]);
            qp_cholesky_solve(w.factor, w.size, rhs, scratch, lam);
            for (int i = 0; i < w.size; i++) {
                const double *gi = p->g + (size_t)w.rows[i] * n;
                for (int j = 0; j < n; j++) target[j] = target[j] - lam[i] * gi[j];
            }
        }
        for (int j = 0; j < n; j++) step[j] = target[j] - x[j];
        /* the longest step towards it that keeps every other row within its bounds */
        double alpha = 1.0, longest = fabs(step[0]), largest = fabs(x[0]);
        int blocking = -1, blocking_side = 0, count = m;
        row_products(p, step, rp);
        for (int j = 1; j < n; j++) {
            if (fabs(step[j]) > longest) longest = fabs(step[j]);
            if (fabs(x[j]) > largest) largest = fabs(x[j]);
        }
        if (longest <= PARALLEL * (1.0 + largest)) count = 0; /* x is the minimiser on W already */
        double small = PARALLEL * longest; /* along p, rows that depend on W change by rounding only */
        for (int row = 0; row < count; row++) {
            double change = rp[row], slack;
            int side;
            if (fabs(change) <= small * p->norms[row] || w.held[row]) continue;
            if (change > 0.0) slack = upper[row] - rx[row], side = 1;
            else slack = lower[row] - rx[row], side = -1;
            double ratio = slack / change;
            if (ratio < alpha) alpha = ratio > 0.0 ? ratio : 0.0, blocking = row, blocking_side = side;
        }
        if (blocking >= 0) {
            for (int j = 0; j < n; j++) x[j] = x[j] + alpha * step[j];
            for (int i = 0; i < m; i++) rx[i] = rx[i] + alpha * rp[i];
            if (append(p, &w, blocking, blocking_side)) continue;
            /* a row that depends on W blocks only by rounding: x is as good as stationary on W */
        } else {
            memcpy(x, target, (size_t)n * sizeof *x);
            for (int i = 0; i < m; i++) rx[i] = rx[i] + rp[i];
        }
        /* stationary on the working set: optimal when every multiplier has its bound's sign */
        double worst = 0.0;
        int drop = -1;
        for (int i = 0; i < w.size; i++) {
            double signed_ = lam[i] * w.sides[i];
            if (signed_ < worst && lower[w.rows[i]] != upper[w.rows[i]]) /* an equality stays */
                worst = signed_, drop = i;
        }
        if (drop < 0) {
            out->iterations = iterations, out->optimal = 1;
            goto done;
        }
        /* the rows after the dropped one are appended again, in their order (each to a slot before its own) */
        int size = w.size;
        for (int i = drop; i < size; i++) w.held[w.rows[i]] = 0;
        w.size = drop;
        for (int i = drop + 1; i < size; i++) append(p, &w, w.rows[i], w.sides[i]);
    }
    out->iterations = iterations, out->optimal = 0;
done:
    out->n_active = w.size;
    memcpy(out->active, w.rows, (size_t)w.size * sizeof *out->active);
    memcpy(out->sides, w.sides, (size_t)w.size * sizeof *out->sides);
}
