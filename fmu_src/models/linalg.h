/*
 * Small dense linear algebra for the controller designs inside the FMUs: the native twin of
 * crane_fmu/model/linalg.py, operation for operation (sums left to right from 0.0, the same pivots,
 * the same Taylor terms), so that a design gives the Python design's bits, on every platform: it needs
 * no libm (not even log2). Matrices are values (no pointers) of at most LA_MAX rows and columns.
 * A function that can fail returns NULL or the Python exception's text ("Type: message", as the
 * Python FMU logs it) and leaves *out unspecified.
 */
#ifndef LINALG_H
#define LINALG_H

#define LA_MAX 13 /* the ZOH's augmented matrix of 8 states and 5 inputs (the estimator's noise model with two forces) */

typedef struct {
    int rows, cols;
    double v[LA_MAX][LA_MAX];
} Matrix;

Matrix la_zeros(int rows, int cols);
Matrix la_identity(int n);
Matrix la_transpose(Matrix a);
Matrix la_add(Matrix a, Matrix b, double scale); /* a + scale * b */
Matrix la_scaled(Matrix a, double s);
double la_dot(const double a[], const double b[], int n); /* linalg.dot: total() of the products */
Matrix la_matmul(Matrix a, Matrix b);
double la_norm1(Matrix a); /* the largest absolute column sum */
const char *la_solve(Matrix a, Matrix b, Matrix *out); /* a^-1 b, Gauss-Jordan with partial pivoting */
int la_ceil_log2(double y);                            /* math.ceil(math.log2(y)), y > 1 finite, no libm */
const char *la_expm(Matrix a, Matrix *out);            /* scaling and squaring, 20 Taylor terms */
const char *la_zoh(Matrix a, Matrix b, double h, Matrix *ad, Matrix *bd);
const char *la_dare(Matrix a, Matrix b, Matrix q, Matrix r, Matrix *p); /* structure-preserving doubling */

#endif
