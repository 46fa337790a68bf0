/*
 * The actuator limits every controller shares: crane_fmu/model/limits.py's limited(), with Python's
 * min() and max() (the first argument unless the second compares smaller or greater, NaN included).
 */
#ifndef LIMITS_H
#define LIMITS_H

#include <math.h>

static inline double py_max(double a, double b) { return b > a ? b : a; }
static inline double py_min(double a, double b) { return b < a ? b : a; }

/* u within +-u_max, and such that the speed after a step h with u held stays within +-v_max; a trolley already
   faster than v_max is braked at u_max. */
static inline double limited(double u, double dx, double u_max, double v_max, double h) {
    double low = -u_max, high = u_max;
    if (isfinite(v_max)) {
        low = py_max(low, (-v_max - dx) / h), high = py_min(high, (v_max - dx) / h);
        if (low > high) return dx > 0 ? -u_max : u_max;
    }
    return py_min(py_max(u, low), high);
}

#endif
