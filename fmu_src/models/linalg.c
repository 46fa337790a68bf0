/*
 * crane_fmu/model/linalg.py in C, function for function; see linalg.h. Each loop adds in the order the
 * Python comprehension does, so the roundings are the same.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "linalg.h"

Matrix la_zeros(int rows, int cols) {
    Matrix a;
    memset(&a, 0, sizeof a);
    a.rows = rows, a.cols = cols;
    return a;
}

Matrix la_identity(int n) {
    Matrix a = la_zeros(n, n);
    for (int i = 0; i < n; i++) a.v[i][i] = 1.0;
    return a;
}

Matrix la_transpose(Matrix a) {
    Matrix t = la_zeros(a.cols, a.rows);
    for (int i = 0; i < a.rows; i++)
        for (int j = 0; j < a.cols; j++) t.v[j][i] = a.v[i][j];
    return t;
}

Matrix la_add(Matrix a, Matrix b, double scale) {
    for (int i = 0; i < a.rows; i++)
        for (int j = 0; j < a.cols; j++) a.v[i][j] = a.v[i][j] + scale * b.v[i][j];
    return a;
}

Matrix la_scaled(Matrix a, double s) {
    for (int i = 0; i < a.rows; i++)
        for (int j = 0; j < a.cols; j++) a.v[i][j] = s * a.v[i][j];
    return a;
}

double la_dot(const double a[], const double b[], int n) {
    double result = 0.0;
    for (int i = 0; i < n; i++) result += a[i] * b[i];
    return result;
}

Matrix la_matmul(Matrix a, Matrix b) {
    Matrix c = la_zeros(a.rows, b.cols), bt = la_transpose(b);
    for (int i = 0; i < a.rows; i++)
        for (int j = 0; j < b.cols; j++) c.v[i][j] = la_dot(a.v[i], bt.v[j], a.cols);
    return c;
}

/* Python's max() of the column sums: the first unless a later one compares greater. */
double la_norm1(Matrix a) {
    double best = 0.0;
    for (int j = 0; j < a.cols; j++) {
        double column = 0.0;
        for (int i = 0; i < a.rows; i++) column += fabs(a.v[i][j]);
        if (j == 0 || column > best) best = column;
    }
    return best;
}

const char *la_solve(Matrix a, Matrix b, Matrix *out) {
    int n = a.rows, width = n + b.cols;
    double m[LA_MAX][2 * LA_MAX] = {{0.0}}, row[2 * LA_MAX];
    for (int i = 0; i < n; i++) {
        memcpy(m[i], a.v[i], (size_t)n * sizeof(double));
        memcpy(m[i] + n, b.v[i], (size_t)b.cols * sizeof(double));
    }
    for (int k = 0; k < n; k++) {
        int pivot = k; /* max(range(k, n), key=abs(m[i][k])): the first of the largest */
        for (int i = k + 1; i < n; i++)
            if (fabs(m[i][k]) > fabs(m[pivot][k])) pivot = i;
        if (m[pivot][k] == 0.0) return "ZeroDivisionError: singular matrix";
        if (pivot != k) {
            memcpy(row, m[k], sizeof row);
            memcpy(m[k], m[pivot], sizeof row);
            memcpy(m[pivot], row, sizeof row);
        }
        double inv = 1.0 / m[k][k];
        for (int j = 0; j < width; j++) m[k][j] = m[k][j] * inv;
        for (int i = 0; i < n; i++) {
            if (i != k && m[i][k] != 0.0) {
                double f = m[i][k];
                for (int j = 0; j < width; j++) m[i][j] = m[i][j] - f * m[k][j];
            }
        }
    }
    *out = la_zeros(n, b.cols);
    for (int i = 0; i < n; i++) memcpy(out->v[i], m[i] + n, (size_t)b.cols * sizeof(double));
    return NULL;
}

/* math.ceil(math.log2(y)) for a finite y > 1, math.log2 correctly rounded (glibc's, CPython's), without libm:
   y = 2^k (1 + n 2^-52) with 0 <= n < 2^52 has log2 y = k + n 2^-52 / ln 2 (1 - O(n 2^-52)), which rounds to k
   when n = 0 or n 2^-52 / ln 2 < ulp(k) / 2 = 2^(j-53), j = floor(log2 k): n < ln 2 * 2^(j-1) (never a tie). */
int la_ceil_log2(double y) {
    uint64_t u;
    memcpy(&u, &y, sizeof u);
    int k = (int)(u >> 52 & 0x7ff) - 1023, j = 0;
    uint64_t n = u & (((uint64_t)1 << 52) - 1);
    if (n == 0) return k;
    while (k >> (j + 1)) j++;
    return k >= 1 && (double)n < 0.5 * 0.69314718055994530942 * (double)(1 << j) ? k : k + 1;
}

const char *la_expm(Matrix a, Matrix *out) {
    int squarings = 0; /* ceil(log2(||a||_1 / 0.5)) */
    double norm = la_norm1(a);
    if (norm > 0.5) {
        if (!isfinite(norm / 0.5)) return "OverflowError: cannot convert float infinity to integer"; /* math.ceil */
        squarings = la_ceil_log2(norm / 0.5);
    }
    double scale = 1.0; /* 0.5 ** squarings: exact (a subnormal power of two, or 0 beyond 2^-1074 as pow gives) */
    for (int i = 0; i < squarings; i++) scale *= 0.5;
    a = la_scaled(a, scale);
    Matrix result = la_identity(a.rows), term = la_identity(a.rows);
    for (int k = 1; k <= 20; k++) {
        term = la_scaled(la_matmul(term, a), 1.0 / k);
        result = la_add(result, term, 1.0);
    }
    for (int i = 0; i < squarings; i++) result = la_matmul(result, result);
    *out = result;
    return NULL;
}

/* expm([[a, b], [0, 0]] h) = [[Ad, Bd], [0, I]] */
const char *la_zoh(Matrix a, Matrix b, double h, Matrix *ad, Matrix *bd) {
    int n = a.rows, m = b.cols;
    Matrix aug = la_zeros(n + m, n + m), e;
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) aug.v[i][j] = h * a.v[i][j];
        for (int j = 0; j < m; j++) aug.v[i][n + j] = h * b.v[i][j];
    }
    const char *error = la_expm(aug, &e);
    if (error) return error;
    *ad = la_zeros(n, n), *bd = la_zeros(n, m);
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) ad->v[i][j] = e.v[i][j];
        for (int j = 0; j < m; j++) bd->v[i][j] = e.v[i][n + j];
    }
    return NULL;
}

/* P = a'Pa - a'Pb (r + b'Pb)^-1 b'Pa + q by doubling (Chu, Fan, Lin, Wang 2004), tol 1e-13, 100 iterations:
   A <- A (I + G H)^-1 A, G <- G + A (I + G H)^-1 G A', H <- H + A' H (I + G H)^-1 A; H converges to P. */
const char *la_dare(Matrix a, Matrix b, Matrix q, Matrix r, Matrix *p) {
    const double tol = 1e-13;
    int n = a.rows;
    Matrix r_inv, w_a, w_g, ak = a, hk = q;
    const char *error = la_solve(r, la_identity(r.rows), &r_inv);
    if (error) return error;
    Matrix gk = la_matmul(b, la_matmul(r_inv, la_transpose(b)));
    for (int iteration = 0; iteration < 100; iteration++) {
        Matrix w = la_add(la_identity(n), la_matmul(gk, hk), 1.0);
        if ((error = la_solve(w, ak, &w_a)) || (error = la_solve(w, gk, &w_g))) return error;
        Matrix h_next = la_add(hk, la_matmul(la_transpose(ak), la_matmul(hk, w_a)), 1.0);
        Matrix g_next = la_add(gk, la_matmul(ak, la_matmul(w_g, la_transpose(ak))), 1.0);
        ak = la_matmul(ak, w_a);
        double change = la_norm1(la_add(h_next, hk, -1.0));
        hk = h_next, gk = g_next;
        double size = la_norm1(hk);
        if (change <= tol * (size > 1.0 ? size : 1.0)) { /* max(1.0, size) */
            *p = hk;
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) p->v[i][j] = 0.5 * (hk.v[i][j] + hk.v[j][i]);
            return NULL;
        }
    }
    return "ArithmeticError: the Riccati iteration did not converge: is the system stabilisable?";
}
