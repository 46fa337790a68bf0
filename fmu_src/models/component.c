/*
 * What every native component does alike (component.h), the C twin of fmu_src/python/runtime.py's Runtime: the
 * start values, the gets and sets with their checks and messages, the outputs (before initialisation they follow
 * the parameters), initialisation and steps. A component's model is one block of plain data (an FMU state is a
 * copy of it):
 *
 *   Block    whether initialisation has ended, then every Real by value reference (the outputs as last computed)
 *   strings  the String variables' values, in table order
 *   config   what configure() made when initialisation ended (before that: scratch for the outputs)
 *   state    the component's state (likewise)
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "component.h"
#include "py_repr.h"

typedef struct {
    int initialised;
    double values[]; /* n_variables */
} Block;

#define ALIGN(n) (((n) + 15) / 16 * 16)
#define R(value) py_repr(value, (char[REPR_SIZE]){0})

static size_t strings_at(const Component *k) { return offsetof(Block, values) + k->n_variables * sizeof(double); }
static size_t config_at(const Component *k) { return ALIGN(strings_at(k) + k->n_strings * sizeof(StringValue)); }
static size_t state_at(const Component *k) { return ALIGN(config_at(k) + k->config_size); }

size_t component_size(const ModelType *type) {
    const Component *k = type->kind;
    return ALIGN(state_at(k) + k->state_size);
}

static StringValue *strings(const Component *k, Block *b) { return (StringValue *)((char *)b + strings_at(k)); }
/* The same, as configure() reads them (C99 does not convert StringValue * to const StringValue * by itself). */
static const StringValue *read_strings(const Component *k, Block *b) { return (const StringValue *)strings(k, b); }
static void *config(const Component *k, Block *b) { return (char *)b + config_at(k); }
static void *state(const Component *k, Block *b) { return k->state_size ? (char *)b + state_at(k) : NULL; }

/* The position of String variable `vr` among the table's Strings. */
static unsigned slot(const Component *k, unsigned vr) {
    unsigned n = 0;
    for (unsigned i = 0; i < vr; i++) n += k->variables[i].type == STRING;
    return n;
}

ModelStatus component_instantiate(const ModelType *type, void *m, const Instantiation *at, const Reporter *r) {
    (void)at, (void)r;
    const Component *k = type->kind;
    Block *b = m;
    b->initialised = 0;
    for (unsigned i = 0; i < k->n_variables; i++) {
        b->values[i] = k->variables[i].start;
        if (k->variables[i].type == STRING) snprintf(strings(k, b)[slot(k, i)], STRING_SIZE, "%s", k->variables[i].text);
    }
    return MODEL_OK;
}

ModelStatus component_exit_initialization(const ModelType *type, void *m, const Reporter *r) {
    const Component *k = type->kind;
    Block *b = m;
    ModelStatus status = k->configure(b->values, read_strings(k, b), config(k, b), r);
    if (status != MODEL_OK) return status;
    if (k->initial_state) k->initial_state(b->values, config(k, b), state(k, b));
    b->initialised = 1;
    return MODEL_OK;
}

/* Every output into the block's values; before initialisation ends, from the parameters (configure() and
   initial_state() into the block's config and state, unused until then). */
static ModelStatus compute_outputs(const Component *k, Block *b, const Reporter *r) {
    if (!b->initialised) {
        if (k->configure(b->values, read_strings(k, b), config(k, b), r) != MODEL_OK) return MODEL_ERROR;
        if (k->initial_state) k->initial_state(b->values, config(k, b), state(k, b));
    }
    return k->outputs(b->values, config(k, b), state(k, b), &b->values[k->first_output], r);
}

static ModelStatus no_variable(const char *model, unsigned vr, const Reporter *r) {
    return report(r, MODEL_ERROR, "%s has no variable with value reference %u", model, vr);
}

ModelStatus component_get_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, double v[],
                                const Reporter *r) {
    const Component *k = type->kind;
    Block *b = m;
    int have_outputs = 0;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= k->n_variables) return no_variable(type->identifier, vr[i], r);
        const VariableRow *row = &k->variables[vr[i]];
        if (row->type == STRING)
            return report(r, MODEL_ERROR, "%s of %s is a String, not a Real", row->name, type->identifier);
        if (row->causality == OUTPUT && !have_outputs) {
            ModelStatus status = compute_outputs(k, b, r);
            if (status != MODEL_OK) return status;
            have_outputs = 1;
        }
        v[i] = b->values[vr[i]];
    }
    return MODEL_OK;
}

ModelStatus store_reals(const char *model, const VariableRow table[], unsigned n_variables, double store[],
                        const unsigned vr[], size_t n, const double values[], int fixed_allowed, const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= n_variables) return no_variable(model, vr[i], r);
        const VariableRow *v = &table[vr[i]];
        if (v->type == STRING) return report(r, MODEL_ERROR, "%s of %s is a String, not a Real", v->name, model);
        if (v->causality == OUTPUT)
            return report(r, MODEL_ERROR, "%s is an output of %s; only parameters and inputs can be set", v->name,
                          model);
        if (v->causality == INPUT && !isfinite(values[i]))
            return report(r, MODEL_ERROR, "input %s must be finite, got %s", v->name, R(values[i]));
        if (v->causality == PARAMETER && !fixed_allowed)
            return report(r, MODEL_ERROR, "%s is a fixed parameter of %s: it can be set only before initialisation ends",
                          v->name, model);
    }
    for (size_t i = 0; i < n; i++) store[vr[i]] = values[i];
    return MODEL_OK;
}

ModelStatus component_set_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, const double v[],
                                int fixed_allowed, const Reporter *r) {
    const Component *k = type->kind;
    return store_reals(type->identifier, k->variables, k->n_variables, ((Block *)m)->values, vr, n, v, fixed_allowed,
                       r);
}

/* The String variable `vr`, or NULL after reporting why not. */
static const VariableRow *string_row(const ModelType *type, unsigned vr, const Reporter *r) {
    const Component *k = type->kind;
    if (vr >= k->n_variables) return no_variable(type->identifier, vr, r), NULL;
    if (k->variables[vr].type != STRING)
        return report(r, MODEL_ERROR, "%s of %s is a Real, not a String", k->variables[vr].name, type->identifier), NULL;
    return &k->variables[vr];
}

ModelStatus component_get_strings(const ModelType *type, void *m, const unsigned vr[], size_t n, const char *v[],
                                  const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        if (!string_row(type, vr[i], r)) return MODEL_ERROR;
        v[i] = strings(type->kind, m)[slot(type->kind, vr[i])]; /* valid until the next call, as FMI allows */
    }
    return MODEL_OK;
}

ModelStatus component_set_strings(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                  const char *const v[], int fixed_allowed, const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        const VariableRow *row = string_row(type, vr[i], r);
        if (!row) return MODEL_ERROR;
        if (!v[i]) return report(r, MODEL_ERROR, "%s must be a string, got NULL", row->name);
        if (strlen(v[i]) >= STRING_SIZE)
            return report(r, MODEL_ERROR, "%s must be a string of at most %d characters, got a longer one", row->name,
                          STRING_SIZE - 1);
        if (!fixed_allowed)
            return report(r, MODEL_ERROR, "%s is a fixed parameter of %s: it can be set only before initialisation ends",
                          row->name, type->identifier);
    }
    for (size_t i = 0; i < n; i++) snprintf(strings(type->kind, m)[slot(type->kind, vr[i])], STRING_SIZE, "%s", v[i]);
    return MODEL_OK;
}

ModelStatus component_do_step(const ModelType *type, void *m, double time, double step, const Reporter *r) {
    const Component *k = type->kind;
    Block *b = m;
    return k->update ? k->update(b->values, config(k, b), state(k, b), time, step, r) : MODEL_OK;
}
