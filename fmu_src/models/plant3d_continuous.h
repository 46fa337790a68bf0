/*
 * The CranePlant3D as a host integrates it (Model Exchange): the C of crane_fmu/model/plant3d_continuous.py,
 * operation for operation. The continuous state is the spatial swing-and-hoist state followed by the two drives'
 * accelerations; the limits that switch are event indicators, and which of them hold is the mode.
 */
#ifndef PLANT3D_CONTINUOUS_H
#define PLANT3D_CONTINUOUS_H

#include "plant3d_equations.h"

enum { DRIVE_X3 = N_SPATIAL, DRIVE_Y3, N_CONTINUOUS3 }; /* the drives' accelerations, after the swing and hoist */
enum { N_INPUTS3 = 7, N_INDICATORS3 = 12, N_OUTPUTS3 = 25 };
enum { IN_UX, IN_UY, IN_HOIST, IN_F1X, IN_F1Y, IN_F2X, IN_F2Y }; /* the inputs' positions (plant3d_continuous.IN) */

/* One horizontal axis' drive and rail (plant3d.Axis). */
typedef struct {
    double u_max, v_max, tau, low, high;
} Axis;

/* The parameters the continuous plant needs (plant3d.Config less its RK4's). */
typedef struct {
    PlantParameters p;
    double c1, c2;
    Axis x, y;
    double l1_min, l1_max, dl1_max;
} ContinuousPlant3;

/* Which limits hold: the trolley's speed along x and y, the cable's length, the cable's speed; each -1, 0, +1. */
typedef struct {
    int speed_x, speed_y, cable, hoist;
} PlantMode3;

enum { PLANT3_OK = 0, PLANT3_F2_WITHOUT_MASS = 1, PLANT3_NOT_FINITE = 2 };

/* The derivatives f of the state s with the inputs; with seeds (ds, din not NULL) also their derivative along them
   into df. Returns PLANT3_OK, or why not (a force on m2 = 0; a derivative not finite). */
int plant3_derivatives(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                       PlantMode3 mode, const double *ds, const double *din, double f[N_CONTINUOUS3], double *df);

/* The CranePlant3D's outputs in table order (ddx, ddy the trolley's accelerations now), and with seeds their
   derivative. */
void plant3_outputs(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                    PlantMode3 mode, const double *ds, const double *din, double out[N_OUTPUTS3], double *dout);

/* The event indicators in the order of plant3d_continuous.INDICATORS: each positive while its mode stays. */
void plant3_event_indicators(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                             PlantMode3 mode, double z[N_INDICATORS3]);

/* What an event update did beside changing the state and mode. */
typedef struct {
    int rail_end;                /* the trolley at a rail end, moving past it: -1 (min), +1 (max), 0 none */
    int rail_axis;               /* 0: x, 1: y */
    int cable_reached;           /* the cable reached a limit while moving */
    double cable_at, cable_rate; /* where, and at what rate */
} PlantEvent3;

/* The event update (also at the end of initialisation): the state and mode in place. */
void plant3_event_update(const ContinuousPlant3 *c, double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                         PlantMode3 *mode, PlantEvent3 *event);

#endif
