/*
 * What the model files do alike with their generated variable table (<model>_variables.h, included
 * first, with model.h, math.h, stdio.h, string.h and py_repr.h): check a set of Reals, all before any
 * is stored, and store them; a model's one String parameter, or none; the Python FMU's messages (the
 * rules of parameters.py, its errors); Python's repr() of a str, max() and min(); limits.limited().
 */
#ifndef MODEL_VALUES_H
#define MODEL_VALUES_H

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

#define STRING_SIZE 256 /* the longest String value kept, with its terminating zero */
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

static inline ModelStatus no_variable(const Reporter *r, unsigned vr) {
    return report(r, MODEL_ERROR, "%s has no variable with value reference %u", MODEL_IDENTIFIER, vr);
}

static inline ModelStatus not_real(const Reporter *r, unsigned vr) {
    return report(r, MODEL_ERROR, "%s of %s is a String, not a Real", VARIABLE_TABLE[vr].name, MODEL_IDENTIFIER);
}

static inline ModelStatus not_string(const Reporter *r, unsigned vr) {
    if (vr >= N_VARIABLES) return no_variable(r, vr);
    return report(r, MODEL_ERROR, "%s of %s is a Real, not a String", VARIABLE_TABLE[vr].name, MODEL_IDENTIFIER);
}

/* Check n Reals to set, all before any is stored, and store them. */
static inline ModelStatus set_real_values(double store[], const unsigned vr[], size_t n, const double values[],
                                          int fixed_allowed, const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VARIABLES) return no_variable(r, vr[i]);
        const VariableRow *v = &VARIABLE_TABLE[vr[i]];
        if (v->type == STRING) return not_real(r, vr[i]);
        if (v->causality == OUTPUT)
            return report(r, MODEL_ERROR, "%s is an output of %s; only parameters and inputs can be set", v->name,
                          MODEL_IDENTIFIER);
        if (v->causality == INPUT && !isfinite(values[i]))
            return report(r, MODEL_ERROR, "input %s must be finite, got %s", v->name,
                          py_repr(values[i], (char[REPR_SIZE]){0}));
        if (v->causality == PARAMETER && !fixed_allowed)
            return report(r, MODEL_ERROR,
                          "%s is a fixed parameter of %s: it can be set only before initialisation ends", v->name,
                          MODEL_IDENTIFIER);
    }
    for (size_t i = 0; i < n; i++) store[vr[i]] = values[i];
    return MODEL_OK;
}

/* Set a model's one String parameter (value reference `svr`, kept in `store`), all or none; `allowed` says which
   values configure() takes ("one of derived, printed"), for the message on a value too long to keep. */
static inline ModelStatus set_string_value(char store[STRING_SIZE], unsigned svr, const char *allowed,
                                           const unsigned vr[], size_t n, const char *const values[], int fixed_allowed,
                                           const Reporter *r) {
    const char *name = VARIABLE_TABLE[svr].name;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != svr) return not_string(r, vr[i]);
        if (!values[i]) return report(r, MODEL_ERROR, "%s must be a string, got NULL", name);
        if (strlen(values[i]) >= STRING_SIZE)
            return report(r, MODEL_ERROR, "%s must be %s, got a string longer than %d characters", name, allowed,
                          STRING_SIZE - 1);
        if (!fixed_allowed)
            return report(r, MODEL_ERROR,
                          "%s is a fixed parameter of %s: it can be set only before initialisation ends", name,
                          MODEL_IDENTIFIER);
    }
    for (size_t i = 0; i < n; i++) snprintf(store, STRING_SIZE, "%s", values[i]);
    return MODEL_OK;
}

/* Get a model's one String parameter: valid until the next call on the instance, as FMI allows. */
static inline ModelStatus get_string_value(const char store[STRING_SIZE], unsigned svr, const unsigned vr[],
                                           size_t n, const char *values[], const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        if (vr[i] != svr) return not_string(r, vr[i]);
        values[i] = store;
    }
    return MODEL_OK;
}

/* The String functions of a model with no String variables (MODEL_N_STRINGS = 0: the frameworks never call them). */
/* What every model file exports alike (model.h): its name, token, size and counts, and model_set_reals, the
   check-and-store of set_real_values() into the model's `values`. */
#define MODEL_EXPORTS(n_strings)                                                                                  \
    const char *const MODEL_NAME = MODEL_IDENTIFIER;                                                              \
    const char *const MODEL_TOKEN = INSTANTIATION_TOKEN;                                                          \
    const size_t MODEL_SIZE = sizeof(Model);                                                                      \
    const unsigned MODEL_N_VARIABLES = N_VARIABLES;                                                               \
    const unsigned MODEL_N_STRINGS = n_strings;                                                                   \
    ModelStatus model_set_reals(Model *m, const unsigned vr[], size_t n, const double values[], int fixed_allowed, \
                                const Reporter *r) {                                                              \
        return set_real_values(m->values, vr, n, values, fixed_allowed, r);                                       \
    }

#define MODEL_WITHOUT_STRINGS                                                                                        \
    ModelStatus model_set_strings(Model *m, const unsigned vr[], size_t n, const char *const values[],               \
                                  int fixed_allowed, const Reporter *r) {                                            \
        (void)m, (void)vr, (void)n, (void)values, (void)fixed_allowed;                                               \
        return report(r, MODEL_ERROR, "this FMU has no variables of this type");                                     \
    }                                                                                                                \
    ModelStatus model_get_strings(Model *m, const unsigned vr[], size_t n, const char *values[], const Reporter *r) { \
        (void)m, (void)vr, (void)n, (void)values;                                                                    \
        return report(r, MODEL_ERROR, "this FMU has no variables of this type");                                     \
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
