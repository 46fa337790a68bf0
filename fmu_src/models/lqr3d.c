/*
 * The LqrController3D component in C: the native twin of crane_fmu/model/lqr3d.py, registered as a component
 * (component.h). Its variables, value references, start values and parameter rules come from
 * LqrController3D_variables.h, generated from lqr3d.VARIABLES. Each axis' design is the planar one of its block of
 * the plant's linearisation at rest, which is the planar crane's (lqr_design.c's continuous_model(); the Python
 * reads the block of plant3d.linearised(), equal to it number for number: tests/test_lqr3d.py); the designs are
 * done when initialisation ends. No state: ux and uy follow the inputs of the same instant. With offset_free, each
 * axis regulates to the rest its estimated forces hold (lqr3d.control(): lqr.force_target(), as lqr.c's).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "LqrController3D_variables.h"
#include "lqr_design.h"
#include "py_repr.h"
#include "rules.h"

enum { N_AXES = 2 }; /* lqr3d.AXES: x, y */

/* lqr3d.Config: each axis's gains and target, the limits and the step, the offset-free target's choice and its
   crane model (lqr.force_target()). */
typedef struct {
    double gains[N_AXES][N_STATE], targets[N_AXES], u_max, v_max, h;
    double offset_free;
    PlantParameters plant;
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
/* Each axis' estimated forces (lqr3d.axis_forces()): on the load, then on the hook. */
static const unsigned FORCES[N_AXES][2] = {{VR_F2x_hat, VR_F1x_hat}, {VR_F2y_hat, VR_F1y_hat}};

/* lqr3d.configure(), after its RULES: each axis's design (lqr.design_of() of the axis' block). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    Matrix a, b;
    const char *error = continuous_model(&p, &a, &b);
    for (int k = 0; k < N_AXES && !error; k++) error = lqr_design_of(a, b, &values[VR_q_x], V(r), V(h), c->gains[k]);
    if (error) return report(r, MODEL_ERROR, "%s", error);
    c->targets[0] = V(x_d), c->targets[1] = V(y_d);
    c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
    c->offset_free = V(offset_free), c->plant = p;
    return MODEL_OK;
}

/* lqr3d.control() per axis: u = dd_ref - K (s - s_ref), s_ref = (ref + target, ...) moved by the axis' estimated
   forces (offset-free), within limits.limited(). */
static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    for (int k = 0; k < N_AXES; k++) {
        double error[N_STATE];
        for (int i = 0; i < N_STATE; i++) error[i] = values[MEASURED[k][i]] - values[REFERENCES[k][i]];
        error[0] -= c->targets[k];
        double f2 = values[FORCES[k][0]], f1 = values[FORCES[k][1]];
        if (c->offset_free != 0.0 && (f2 != 0.0 || f1 != 0.0)) { /* lqr.force_target(): the rest the forces hold
                                                                     (eqs (8)-(9) at rest) */
            const PlantParameters *p = &c->plant;
            double theta1 = (f1 + f2) / ((p->m1 + p->m2) * p->g), theta2 = f2 / (p->m2 * p->g);
            if (c->offset_free == 1.0) error[0] -= -(p->l1 * theta1 + p->l2 * theta2); /* the load at the target */
            error[2] -= theta1, error[4] -= theta2;
        }
        out[k] = limited(values[DD_REF[k]] - la_dot(c->gains[k], error, N_STATE), values[MEASURED[k][1]], c->u_max,
                         c->v_max, c->h);
    }
    return MODEL_OK;
}

STATELESS_COMPONENT;
