/*
 * What the model files share of the Python models: the language of the parameter rules (crane_fmu/model/rules.py)
 * that the generated variable headers check, the Python FMU's messages where its model divides by zero or takes
 * the root of a negative number, Python's repr() of a float and a str, max() and min(); limits.unlimited() and
 * limits.limited().
 */
#ifndef RULES_H
#define RULES_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "component.h"
#include "py_repr.h"

/* Python's repr() of a double (py_repr.h) and of a str (str_repr below), in a buffer that lives as long as the
   statement: the values a rule's message shows. */
#define REPR(value) py_repr(value, (char[REPR_SIZE]){0})
#define STR_REPR(text) str_repr(text, (char[STR_REPR_SIZE]){0})

/* rules.whole(): finite, with no fraction. */
static inline int is_whole(double value) { return isfinite(value) && value == trunc(value); }

/* The Python FMU's messages where its model divides by zero or takes the square root of a negative number. */
#define ZERO_DIVISION(r) report(r, MODEL_ERROR, "ZeroDivisionError: float division by zero")
#define DOMAIN_ERROR(r) report(r, MODEL_ERROR, "math domain error")

#define STR_REPR_SIZE (4 * STRING_SIZE + 3)

/* Python's repr() of a str: quotes and escapes as CPython chooses them (bytes >= 0x80 kept as they are). */
static inline char *str_repr(const char *s, char out[STR_REPR_SIZE]) {
    int single = strchr(s, '\'') != NULL && strchr(s, '"') == NULL ? 0 : 1;
    char quote = single ? '\'' : '"', *o = out;
    *o++ = quote;
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '\\' || *p == (unsigned char)quote) *o++ = '\\', *o++ = (char)*p;
        else if (*p == '\n') *o++ = '\\', *o++ = 'n';
        else if (*p == '\r') *o++ = '\\', *o++ = 'r';
        else if (*p == '\t') *o++ = '\\', *o++ = 't';
        else if (*p < 0x20 || *p == 0x7f) o += sprintf(o, "\\x%02x", *p);
        else *o++ = (char)*p;
    }
    *o++ = quote, *o = 0;
    return out;
}

/* Python's max(a, b) and min(a, b): the first unless the second compares greater (smaller). */
static inline double py_max(double a, double b) { return b > a ? b : a; }
static inline double py_min(double a, double b) { return b < a ? b : a; }

/* limits.unlimited(): a limit at or beyond +-1e60 (NO_LIMIT, the start value of a limit that is off) is none. */
static inline double unlimited(double value) { return value >= 1e60 ? INFINITY : value <= -1e60 ? -INFINITY : value; }

/* limits.limited(u, dx, u_max, v_max, h): u within +-u_max, and the speed after the step h within +-v_max. */
static inline double limited(double u, double dx, double u_max, double v_max, double h) {
    double low = -u_max, high = u_max;
    if (isfinite(v_max)) {
        low = py_max(low, (-v_max - dx) / h), high = py_min(high, (v_max - dx) / h);
        if (low > high) return dx > 0 ? -u_max : u_max;
    }
    return py_min(py_max(u, low), high);
}

#endif
