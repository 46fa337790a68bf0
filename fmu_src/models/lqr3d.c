/*
 * The LqrController3D component in C: the native twin of crane_fmu/model/lqr3d.py, registered as a component
 * (component.h). Its variables, value references, start values and parameter rules come from
 * LqrController3D_variables.h, generated from lqr3d.VARIABLES. Each axis' design is the planar one of its block of
 * the plant's linearisation at rest, which is the planar crane's (lqr_design.c's continuous_model(); the Python
 * reads the block of plant3d.linearised(), equal to it number for number: tests/test_lqr3d.py); the designs are
 * done when initialisation ends. No state: ux and uy follow the inputs of the same instant.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "LqrController3D_variables.h"
#include "lqr_design.h"
#include "py_repr.h"
#include "rules.h"

enum { N_AXES = 2 }; /* lqr3d.AXES: x, y */

/* lqr3d.Config: each axis's gains and target, the limits and the step. */
typedef struct {
    double gains[N_AXES][N_STATE], targets[N_AXES], u_max, v_max, h;
} Config;

#define V(name) (values[VR_##name])

/* Each axis' states (lqr3d.axis_states()), its references and its feedforward, by value reference. */
static const unsigned MEASURED[N_AXES][N_STATE] = {
    {VR_x, VR_dx, VR_theta1x, VR_dtheta1x, VR_theta2x, VR_dtheta2x},
    {VR_y, VR_dy, VR_theta1y, VR_dtheta1y, VR_theta2y, VR_dtheta2y}};
static const unsigned REFERENCES[N_AXES][N_STATE] = {
    {VR_x_ref, VR_dx_ref, VR_theta1x_ref, VR_dtheta1x_ref, VR_theta2x_ref, VR_dtheta2x_ref},
    {VR_y_ref, VR_dy_ref, VR_theta1y_ref, VR_dtheta1y_ref, VR_theta2y_ref, VR_dtheta2y_ref}};
static const unsigned DD_REF[N_AXES] = {VR_ddx_ref, VR_ddy_ref};

/* lqr3d.configure(), after its RULES: each axis's design (lqr.design_of() of the axis' block). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    Matrix a, b;
    const char *error = continuous_model(&p, &a, &b);
    for (int k = 0; k < N_AXES && !error; k++) error = lqr_design_of(a, b, &values[VR_q_x], V(r), V(h), c->gains[k]);
    if (error) return report(r, MODEL_ERROR, "%s", error);
    c->targets[0] = V(x_d), c->targets[1] = V(y_d);
    c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
    return MODEL_OK;
}

/* lqr3d.control() per axis: u = dd_ref - K (s - s_ref), s_ref = (ref + target, ...), within limits.limited(). */
static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    for (int k = 0; k < N_AXES; k++) {
        double error[N_STATE];
        for (int i = 0; i < N_STATE; i++) error[i] = values[MEASURED[k][i]] - values[REFERENCES[k][i]];
        error[0] -= c->targets[k];
        out[k] = limited(values[DD_REF[k]] - la_dot(c->gains[k], error, N_STATE), values[MEASURED[k][1]], c->u_max,
                         c->v_max, c->h);
    }
    return MODEL_OK;
}

STATELESS_COMPONENT;
