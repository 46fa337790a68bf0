/*
 * The crane's equations of motion, eqs (4)-(9) of the paper, extended by hoisting, horizontal
 * forces and joint damping: the C of crane_fmu/model/plant_equations.py, operation for operation
 * (compiled with -ffp-contract=off, it gives that module's numbers).
 */
#ifndef PLANT_EQUATIONS_H
#define PLANT_EQUATIONS_H

/* positions in the swing-and-hoist state */
enum { X, DX, THETA1, DTHETA1, THETA2, DTHETA2, L1, DL1, N_SWING };

typedef struct {
    double m1, m2, l1, l2, g;
} PlantParameters;

/* What acts beside the trolley acceleration: the hoist acceleration l1'', forces F1, F2 [N] on hook
   and payload, damping c1, c2 [N m s/rad] at the trolley and hook joints. */
typedef struct {
    double hoist, f1, f2, c1, c2;
} Load;

/* Eqs (8)-(9), extended, solved for (ddtheta1, ddtheta2); l1 and dl1 are the main cable's length and rate now. */
void angular_accelerations(double theta1, double dtheta1, double theta2, double dtheta2, double u,
                           const PlantParameters *p, double l1, double dl1, const Load *load, double dd[2]);

/* One RK4 step of the paper's model (no hoisting, no forces, no damping), state[N_SWING] in place. */
void paper_step(double state[N_SWING], double u, double dt, const PlantParameters *p);

/* One classical RK4 step with every effect, state[N_SWING] in place; l1'' is constant over the step. */
void rk4_step(double state[N_SWING], double u, double dt, const PlantParameters *p, const Load *load);

/* The swing state, hook and payload positions x1, y1, x2, y2 (eqs 4-5) and the energy (eqs 6-7). */
void plant_outputs(const double state[N_SWING], const PlantParameters *p, double out[11]);

/* angular_accelerations() into dd and its derivative along `seed` into tdd, exactly: seed is the change of
   (theta1, dtheta1, theta2, dtheta2, u, l1, dl1, l1'', F1, F2). */
void accelerations_tangent(double theta1, double dtheta1, double theta2, double dtheta2, double u,
                           const PlantParameters *p, double l1, double dl1, const Load *load, const double seed[10],
                           double dd[2], double tdd[2]);

/* The derivative of plant_outputs() along a change t of the state. */
void outputs_tangent(const double state[N_SWING], const PlantParameters *p, const double t[N_SWING], double out[11]);

#endif
