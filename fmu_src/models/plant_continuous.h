/*
 * The CranePlant as a host integrates it (Model Exchange): the C of crane_fmu/model/plant_continuous.py,
 * operation for operation. The continuous state is the swing and hoist state followed by the drive's
 * acceleration; the derivatives are angular_accelerations(), the function the co-simulation's RK4 calls,
 * with the trolley and hoist accelerations the drive and the held limits let through. The limits that
 * switch are event indicators, and which of them hold is the mode (the model's discrete state).
 */
#ifndef PLANT_CONTINUOUS_H
#define PLANT_CONTINUOUS_H

#include "plant_equations.h"

enum { DRIVE_STATE = N_SWING, N_CONTINUOUS };   /* the drive's acceleration, after the swing and hoist state */
enum { N_PLANT_INPUTS = 4, N_INDICATORS = 8, N_PLANT_OUTPUTS = 14 };

/* The parameters the continuous plant needs (plant.Config less its RK4's). */
typedef struct {
    PlantParameters p;
    double c1, c2, u_max, v_max, tau, x_min, x_max, l1_min, l1_max, dl1_max;
} ContinuousPlant;

/* Which limits hold: the trolley's speed, the cable's length, the cable's speed; each -1, 0 (free) or +1. */
typedef struct {
    int speed, cable, hoist;
} PlantMode;

enum { PLANT_OK = 0, PLANT_F2_WITHOUT_MASS = 1, PLANT_NOT_FINITE = 2 };

/* The derivatives f of the state s with inputs (u, hoist, F1, F2); with seeds (ds, din not NULL) also their
   derivative along them into df. Returns PLANT_OK, or why not (F2 on m2 = 0; a derivative not finite). */
int plant_derivatives(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                      PlantMode mode, const double *ds, const double *din, double f[N_CONTINUOUS], double *df);

/* The CranePlant's outputs in table order (ddx the trolley's acceleration now), and with seeds their derivative. */
void plant_continuous_outputs(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                              PlantMode mode, const double *ds, const double *din, double out[N_PLANT_OUTPUTS],
                              double *dout);

/* The event indicators in the order of plant_continuous.INDICATORS: each positive while its mode stays. */
void plant_event_indicators(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                            PlantMode mode, double z[N_INDICATORS]);

/* What an event update did beside changing the state and mode. */
typedef struct {
    int rail_end;            /* the trolley at a rail end, moving past it: -1 (x_min), +1 (x_max), 0 none */
    int cable_reached;       /* the cable reached a limit while moving */
    double cable_at, cable_rate; /* where, and at what rate */
} PlantEvent;

/* The event update (also at the end of initialisation): the state and mode in place. */
void plant_event_update(const ContinuousPlant *c, double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                        PlantMode *mode, PlantEvent *event);

#endif
