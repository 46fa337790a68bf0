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
    int model_exchange; /* the host integrates the component: its outputs are the continuous ones */
    double values[];    /* n_variables */
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

/* The position of String (or Enumeration, kept by name) variable `vr` among the table's Strings. */
static unsigned slot(const Component *k, unsigned vr) {
    unsigned n = 0;
    for (unsigned i = 0; i < vr; i++) n += k->variables[i].type != REAL;
    return n;
}

ModelStatus component_instantiate(const ModelType *type, void *m, const Instantiation *at, const Reporter *r) {
    (void)r;
    const Component *k = type->kind;
    Block *b = m;
    b->initialised = 0;
    b->model_exchange = at->model_exchange && k->continuous;
    for (unsigned i = 0; i < k->n_variables; i++) {
        b->values[i] = k->variables[i].start;
        if (k->variables[i].type != REAL) snprintf(strings(k, b)[slot(k, i)], STRING_SIZE, "%s", k->variables[i].text);
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
/* Before initialisation ends: the config and initial state from the parameters, into the block's scratch. */
static ModelStatus from_parameters(const Component *k, Block *b, const Reporter *r) {
    if (!b->initialised) {
        if (k->configure(b->values, read_strings(k, b), config(k, b), r) != MODEL_OK) return MODEL_ERROR;
        if (k->initial_state) k->initial_state(b->values, config(k, b), state(k, b));
    }
    return MODEL_OK;
}

static ModelStatus compute_outputs(const Component *k, Block *b, const Reporter *r) {
    if (from_parameters(k, b, r) != MODEL_OK) return MODEL_ERROR;
    if (b->model_exchange) {
        k->continuous->outputs(b->values, config(k, b), state(k, b), 1, NULL, NULL, &b->values[k->first_output],
                               NULL);
        return MODEL_OK;
    }
    return k->outputs(b->values, config(k, b), state(k, b), &b->values[k->first_output], r);
}

static ModelStatus local_value(const ModelType *type, Block *b, unsigned vr, double *v, const Reporter *r);

static ModelStatus no_variable(const char *model, unsigned vr, const Reporter *r) {
    return report(r, MODEL_ERROR, "%s has no variable with value reference %u", model, vr);
}

ModelStatus component_get_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, double v[],
                                const Reporter *r) {
    const Component *k = type->kind;
    Block *b = m;
    int have_outputs = 0;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= k->n_variables && k->continuous && vr[i] < k->n_variables + k->continuous->n_locals) {
            ModelStatus status = local_value(type, b, vr[i], &v[i], r);
            if (status != MODEL_OK) return status;
            continue;
        }
        if (vr[i] >= k->n_variables) return no_variable(type->identifier, vr[i], r);
        const VariableRow *row = &k->variables[vr[i]];
        if (row->type != REAL)
            return report(r, MODEL_ERROR, "%s of %s is a%s, not a Real", row->name, type->identifier,
                          row->type == STRING ? " String" : "n Enumeration");
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
        if (v->type != REAL)
            return report(r, MODEL_ERROR, "%s of %s is a%s, not a Real", v->name, model,
                          v->type == STRING ? " String" : "n Enumeration");
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

/* The variable `vr` of type `wanted`, or NULL after reporting why not. */
static const VariableRow *typed_row(const ModelType *type, unsigned vr, VariableType wanted, const Reporter *r) {
    static const char *const NAMES[] = {"a Real", "a String", "an Enumeration"};
    const Component *k = type->kind;
    if (vr >= k->n_variables) return no_variable(type->identifier, vr, r), NULL;
    if (k->variables[vr].type != wanted)
        return report(r, MODEL_ERROR, "%s of %s is %s, not %s", k->variables[vr].name, type->identifier,
                      NAMES[k->variables[vr].type], NAMES[wanted]), NULL;
    return &k->variables[vr];
}
static const VariableRow *string_row(const ModelType *type, unsigned vr, const Reporter *r) {
    return typed_row(type, vr, STRING, r);
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

/* ---- Model Exchange (component.h's ContinuousComponent behind model.h's ContinuousModel) ---- */

#define MOST 64 /* continuous states, inputs and outputs a component may have */

/* The position of `vr` among `n` value references, or -1. */
static int position(const unsigned vrs[], unsigned n, unsigned vr) {
    for (unsigned i = 0; i < n; i++)
        if (vrs[i] == vr) return (int)i;
    return -1;
}

static ModelStatus derivatives_now(const Component *k, Block *b, double f[], const Reporter *r) {
    if (from_parameters(k, b, r) != MODEL_OK) return MODEL_ERROR;
    return k->continuous->derivatives(b->values, config(k, b), state(k, b), NULL, NULL, f, NULL, r);
}

static ModelStatus indicators_now(const Component *k, Block *b, double z[], const Reporter *r) {
    if (from_parameters(k, b, r) != MODEL_OK) return MODEL_ERROR;
    k->continuous->indicators(b->values, config(k, b), state(k, b), z);
    return MODEL_OK;
}

/* A Model Exchange variable: a state, a derivative or an event indicator. */
static ModelStatus local_value(const ModelType *type, Block *b, unsigned vr, double *v, const Reporter *r) {
    const Component *k = type->kind;
    const ContinuousComponent *q = k->continuous;
    double values[MOST];
    int i;
    if (from_parameters(k, b, r) != MODEL_OK) return MODEL_ERROR;
    if ((i = position(q->state_vrs, q->n_states, vr)) >= 0) {
        *v = q->states(state(k, b))[i];
    } else if ((i = position(q->derivative_vrs, q->n_states, vr)) >= 0) {
        ModelStatus status = derivatives_now(k, b, values, r);
        if (status != MODEL_OK) return status;
        *v = values[i];
    } else if ((i = position(q->indicator_vrs, q->n_indicators, vr)) >= 0) {
        indicators_now(k, b, values, r);
        *v = values[i];
    } else {
        return no_variable(type->identifier, vr, r);
    }
    return MODEL_OK;
}

ModelStatus component_get_states(const ModelType *type, void *m, double x[], const Reporter *r) {
    const Component *k = type->kind;
    if (from_parameters(k, m, r) != MODEL_OK) return MODEL_ERROR;
    memcpy(x, k->continuous->states(state(k, m)), k->continuous->n_states * sizeof *x);
    return MODEL_OK;
}

ModelStatus component_set_states(const ModelType *type, void *m, const double x[], const Reporter *r) {
    const Component *k = type->kind;
    for (unsigned i = 0; i < k->continuous->n_states; i++)
        if (!isfinite(x[i]))
            return report(r, MODEL_ERROR, "continuous state %u of %s must be finite, got %s", i, type->identifier,
                          R(x[i]));
    memcpy(k->continuous->states(state(k, m)), x, k->continuous->n_states * sizeof *x);
    return MODEL_OK;
}

ModelStatus component_derivatives(const ModelType *type, void *m, double dx[], const Reporter *r) {
    return derivatives_now(type->kind, m, dx, r);
}

ModelStatus component_indicators(const ModelType *type, void *m, double z[], const Reporter *r) {
    return indicators_now(type->kind, m, z, r);
}

ModelStatus component_event_update(const ModelType *type, void *m, double time, int *terminate, const Reporter *r) {
    const Component *k = type->kind;
    Block *b = m;
    return k->continuous->event_update(b->values, config(k, b), state(k, b), time, terminate, r);
}

/* d unknowns / d knowns along `seed`: the knowns are continuous states or inputs, the unknowns derivatives or
   outputs; one forward-mode evaluation of the derivatives and the outputs. In co-simulation the same at the
   communication point, the outputs being co-simulation's (an unknown that is an output and a derivative, such as
   ddx, is the output: what fmi2GetReal gives there). */
ModelStatus component_directional(const ModelType *type, void *m, const unsigned unknowns[], size_t nu,
                                  const unsigned knowns[], size_t nk, const double seed[], double sensitivity[],
                                  const Reporter *r) {
    const Component *k = type->kind;
    const ContinuousComponent *q = k->continuous;
    Block *b = m;
    double ds[MOST] = {0}, din[MOST] = {0}, f[MOST], df[MOST], out[MOST], dout[MOST];
    if (q->n_states > MOST || q->n_inputs > MOST || k->n_outputs > MOST)
        return report(r, MODEL_ERROR, "%s has more than %d states, inputs or outputs", type->identifier, MOST);
    for (size_t j = 0; j < nk; j++) {
        int i = position(q->state_vrs, q->n_states, knowns[j]);
        if (i >= 0) ds[i] += seed[j];
        else if (knowns[j] >= q->first_input && knowns[j] < q->first_input + q->n_inputs)
            din[knowns[j] - q->first_input] += seed[j];
        else
            return report(r, MODEL_ERROR, "value reference %u is neither a continuous state nor an input of %s: "
                          "the derivatives are by those", knowns[j], type->identifier);
    }
    if (from_parameters(k, b, r) != MODEL_OK) return MODEL_ERROR;
    ModelStatus status = q->derivatives(b->values, config(k, b), state(k, b), ds, din, f, df, r);
    if (status != MODEL_OK) return status;
    q->outputs(b->values, config(k, b), state(k, b), b->model_exchange, ds, din, out, dout);
    for (size_t j = 0; j < nu; j++) {
        int i = position(q->derivative_vrs, q->n_states, unknowns[j]);
        if (unknowns[j] >= k->first_output && unknowns[j] < k->n_variables)
            sensitivity[j] = dout[unknowns[j] - k->first_output];
        else if (i >= 0) sensitivity[j] = df[i];
        else
            return report(r, MODEL_ERROR, "value reference %u is neither a derivative nor an output of %s",
                          unknowns[j], type->identifier);
    }
    return MODEL_OK;
}

/* Enumerations: the item kept by name (an unknown name, never stored, would read as 0). */
ModelStatus component_get_integers(const ModelType *type, void *m, const unsigned vr[], size_t n, long long v[],
                                   const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        const VariableRow *row = typed_row(type, vr[i], ENUMERATION, r);
        if (!row) return MODEL_ERROR;
        const char *name = strings(type->kind, m)[slot(type->kind, vr[i])];
        v[i] = 0;
        for (unsigned j = 0; j < row->n_items; j++)
            if (strcmp(name, row->items[j]) == 0) v[i] = j + 1;
    }
    return MODEL_OK;
}

ModelStatus component_set_integers(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                   const long long v[], int fixed_allowed, const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        const VariableRow *row = typed_row(type, vr[i], ENUMERATION, r);
        if (!row) return MODEL_ERROR;
        if (v[i] < 1 || v[i] > (long long)row->n_items) {
            char allowed[512] = "";
            for (unsigned j = 0; j < row->n_items; j++) {
                size_t used = strlen(allowed);
                snprintf(allowed + used, sizeof allowed - used, "%s%u (%s)", j ? ", " : "", j + 1, row->items[j]);
            }
            return report(r, MODEL_ERROR, "%s must be one of %s, got %lld", row->name, allowed, v[i]);
        }
        if (!fixed_allowed)
            return report(r, MODEL_ERROR, "%s is a fixed parameter of %s: it can be set only before initialisation ends",
                          row->name, type->identifier);
    }
    for (size_t i = 0; i < n; i++) {
        const VariableRow *row = &((const Component *)type->kind)->variables[vr[i]];
        snprintf(strings(type->kind, m)[slot(type->kind, vr[i])], STRING_SIZE, "%s", row->items[v[i] - 1]);
    }
    return MODEL_OK;
}
