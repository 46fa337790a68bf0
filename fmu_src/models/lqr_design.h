/*
 * The discrete LQR design of the crane linearised about rest, shared by the native controllers and the state
 * estimator: the C of crane_fmu/model/lqr.py's continuous_model() and design(), operation for operation over
 * linalg.c, so that a design gives the Python design's bits. A function that can fail returns NULL or the
 * Python exception's text.
 */
#ifndef LQR_DESIGN_H
#define LQR_DESIGN_H

#include "linalg.h"
#include "plant_equations.h"

enum { N_STATE = 6 }; /* s = (x, dx, theta1, dtheta1, theta2, dtheta2) */

#define DIVISION_BY_ZERO "ZeroDivisionError: float division by zero" /* Python's, where C would give inf */

/* lqr.continuous_model(): s' = A s + B u with x'' = u (eq 12) and eqs (8)-(9) linearised. */
const char *continuous_model(const PlantParameters *p, Matrix *a, Matrix *b);

/* lqr.design(): the gains K (6) of the discrete LQR for the state weights, the input weight r and the step h. */
const char *lqr_design(const PlantParameters *p, const double weights[N_STATE], double r, double h,
                       double gains[N_STATE]);

/* lqr.design_of(): the gains K (6) of the discrete LQR of one axis s' = A s + B u (6 states, one input). */
const char *lqr_design_of(Matrix a, Matrix b, const double weights[N_STATE], double r, double h,
                          double gains[N_STATE]);

#endif
