/*
 * The overhead crane in three dimensions: the spatial double pendulum under a trolley that moves in x and y, with
 * the hoist, (S1)-(S6) of crane_fmu/model/plant3d_equations.py, operation for operation (compiled with
 * -ffp-contract=off, it gives that module's numbers).
 */
#ifndef PLANT3D_EQUATIONS_H
#define PLANT3D_EQUATIONS_H

#include "plant_equations.h" /* PlantParameters */

/* positions in the spatial swing-and-hoist state */
enum { X3, DX3, Y3, DY3, A1, DA1, B1, DB1, A2, DA2, B2, DB2, L13, DL13, N_SPATIAL };

/* What acts beside the trolley's accelerations: the hoist acceleration l1'', the horizontal forces on hook and load
   [N], the damping at the trolley and hook joints [N m s/rad]. */
typedef struct {
    double hoist, f1x, f1y, f2x, f2y, c1, c2;
} Load3;

/* (S4)-(S6) solved for (dda1, ddb1, dda2, ddb2); angles = (a1, da1, b1, db1, a2, da2, b2, db2); l1 and dl1 are the
   main cable's length and rate now. */
void spatial_accelerations(const double angles[8], double ux, double uy, const PlantParameters *p, double l1,
                           double dl1, const Load3 *load, double dd[4]);

/* spatial_accelerations() into dd and its derivative along `seed` into tdd, exactly: seed is the change of
   (a1, da1, b1, db1, a2, da2, b2, db2, ux, uy, l1, dl1, l1'', F1x, F1y, F2x, F2y). */
void spatial_accelerations_tangent(const double angles[8], double ux, double uy, const PlantParameters *p, double l1,
                                   double dl1, const Load3 *load, const double seed[17], double dd[4], double tdd[4]);

/* One classical RK4 step of the 14-element state in place, the inputs held (l1'' = load->hoist). */
void spatial_rk4_step(double state[N_SPATIAL], double ux, double uy, double dt, const PlantParameters *p,
                      const Load3 *load);

/* Hook and load positions x1, y1, z1, x2, y2, z2, the cables' swing angles and the energy. */
void spatial_outputs(const double state[N_SPATIAL], const PlantParameters *p, double out[9]);

/* The derivative of spatial_outputs() along a change t of the state. */
void spatial_outputs_tangent(const double state[N_SPATIAL], const PlantParameters *p, const double t[N_SPATIAL],
                             double out[9]);

#endif
