/*
 * What the model files share of the Python models (included after their generated variable header, with math.h,
 * stdio.h, string.h and py_repr.h): the rule messages of parameters.py and the configure()s, the crane model's
 * rules, the Python FMU's messages where its model divides by zero or takes the root of a negative number,
 * Python's repr() of a str, max() and min(); limits.unlimited() and limits.limited().
 */
#ifndef RULES_H
#define RULES_H

/* "name must be text, got repr(value)": the rule messages of parameters.py and the configure()s. */
static inline ModelStatus rule(const Reporter *r, const char *name, const char *text, double value) {
    return report(r, MODEL_ERROR, "%s must be %s, got %s", name, text, py_repr(value, (char[REPR_SIZE]){0}));
}

/* parameters.plant_parameters(): the rules of a component's crane model, in their order and words. */
static inline ModelStatus plant_rules(double m1, double m2, double l1, double l2, double g, const Reporter *r) {
    if (!(isfinite(m1) && m1 > 0)) return rule(r, "m1", "> 0 and finite", m1);
    if (!(isfinite(m2) && m2 >= 0)) return rule(r, "m2", ">= 0 and finite", m2);
    if (!(isfinite(l1) && l1 > 0)) return rule(r, "l1", "> 0 and finite", l1);
    if (!(isfinite(l2) && l2 > 0)) return rule(r, "l2", "> 0 and finite", l2);
    if (!(isfinite(g) && g > 0)) return rule(r, "g", "> 0 and finite", g);
    return MODEL_OK;
}

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
