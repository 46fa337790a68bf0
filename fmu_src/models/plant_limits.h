/*
 * The plants' limits (crane_fmu/model/plant_limits.py, plant_continuous.py): a demand limited, a speed kept within
 * its limit over a sub-step, and for Model Exchange the event indicators of a limited quantity and its update at an
 * event. Shared by the planar and the spatial plant, co-simulation and Model Exchange alike.
 */
#ifndef PLANT_LIMITS_H
#define PLANT_LIMITS_H

#include <math.h>

/* Python's min(max(value, low), high). */
static inline double clamp(double value, double low, double high) {
    double v = low > value ? low : value;
    return high < v ? high : v;
}

/* `accel` limited so that `speed` ends the sub-step dt within +-speed_max (plant_limits.within_speed). */
static inline double within_speed(double accel, double speed, double speed_max, double dt) {
    if (speed_max == INFINITY) return accel;
    return clamp(accel, (-speed_max - speed) / dt, (speed_max - speed) / dt);
}

/* limit - value (the room to a limit above), or 1 when there is no limit. */
static inline double room(double value, double limit) { return isfinite(limit) ? limit - value : 1.0; }

/* The event indicators of a quantity's lower and upper limit: the room left while free, the push while held. */
static inline void pair(double value, double low, double high, int held, double pressing, double z[2]) {
    z[0] = held < 0 ? -pressing : room(-value, -low);
    z[1] = held > 0 ? pressing : room(value, high);
}

/* One limited quantity after an event (plant_continuous._hold): let go when pressed away from its limit; set onto
   a limit it reached while moving or pressed towards it (or passed), and held while pressed on. Returns reached. */
static inline int hold(double *value, double rate, double pressing, int *held, double low, double high) {
    if ((*held > 0 && pressing < 0) || (*held < 0 && pressing > 0)) *held = 0;
    if (*held == 0) {
        if (*value > high || (*value == high && (rate > 0 || pressing > 0))) {
            *value = high, *held = pressing > 0 ? 1 : 0;
            return 1;
        }
        if (*value < low || (*value == low && (rate < 0 || pressing < 0))) {
            *value = low, *held = pressing < 0 ? -1 : 0;
            return 1;
        }
    }
    return 0;
}

#endif
