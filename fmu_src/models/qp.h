/*
 * The QP solver of the model-predictive controller: the C of crane_fmu/model/qp.py, operation for operation
 * (every sum left to right from 0.0, the same pivots and tests), so that a solve gives the Python solve's bits.
 *
 *     minimise  1/2 x' H x + f' x   subject to  lower_i <= r_i' x <= upper_i
 *
 * A row r_i is its non-zero span: `length[i]` values from values[offset[i]] at x[first[i]...]. The caller owns
 * every array; qp_prepare() fills a QpPrepared's hinv, g and norms and its chains (qp.chains()); S = R H^-1 R'
 * (qp.py's Prepared.s) is not kept: its rows are made when needed, each as qp.py makes it (row_products of G's).
 */
#ifndef QP_H
#define QP_H

typedef struct {
    int n, m;                         /* variables, rows */
    const int *first, *length, *offset; /* each row's span (m) */
    const double *values;
    double *hinv;  /* n x n */
    double *g;     /* m x n: G = R H^-1 */
    double *norms; /* m: each row's 1-norm */
    int *chain_end; /* m: the last row of the chain a row begins (-1: the row is inside a chain) */
} QpPrepared;

/* The doubles and ints of scratch a solve of n variables and m rows needs (qp_solve's `work`, `iwork`). */
#define QP_WORK(n, m) (3 * (n) + 7 * (m) + (m) * ((m) + 1) / 2)
#define QP_IWORK(m) (3 * (m))

/* qp.cholesky(): the lower-triangular L (n x n, row-major) with L L' = a; -1 when a is not positive definite. */
int qp_cholesky(const double *a, int n, double *factor);

/* qp.prepare(): H^-1 (through qp.inverse_spd, with 2 n^2 doubles of scratch), G, the norms and the chains;
   -1 when H is not positive definite. */
int qp_prepare(QpPrepared *p, const double *h, double *scratch);

/* The result of qp.solve(): x (n, the caller's), the rows held at a bound with their sides (+1 upper, -1 lower;
   the caller's arrays of m), how many, the iterations and whether optimal (0: the cap stopped it). */
typedef struct {
    double *x;
    int *active, *sides, n_active, iterations, optimal;
} QpSolution;

/* qp.solve(): minimise from the feasible `start`, with the hint rows (`hint_rows`, `hint_sides`, n_hint) held at
   their bounds where they are at them. `work` and `iwork`: QP_WORK(n, m) doubles and QP_IWORK(m) ints. */
void qp_solve(const QpPrepared *p, const double *f, const double *lower, const double *upper, const double *start,
              const int *hint_rows, const int *hint_sides, int n_hint, int max_iterations, double *work, int *iwork,
              QpSolution *out);

/* qp.cholesky_solve(): y with L L' y = rhs for L packed by rows (row i: i + 1 values from i (i + 1) / 2). */
void qp_cholesky_solve(const double *packed, int m, const double *rhs, double *scratch, double *y);

#endif
