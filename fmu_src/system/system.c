/*
 * A system of native component models as one model (model.h), so that the FMI frameworks run it as they run
 * any model: one model block per instance, the system's parameter values set after the start values, the
 * connections as copies by value reference in Gauss-Seidel order, and every instance stepped with the
 * system's step (crane_fmu.cosim's master, algorithm gauss-seidel). It reaches the instances' models only
 * through their ModelTypes. All of a system is in the generated system_config.h (build_scripts/one_fmu.py);
 * nothing here names a system or a component.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "system_config.h"
#include "py_repr.h"

/* The system's model: this header, then the instances' model blocks at `offsets`. Plain data. */
typedef struct {
    double values[N_VARIABLES]; /* the system's own parameters and inputs, by value reference */
    int initialised, started, bad_defaults;
    double start;               /* the time of the first step: inner times are start + k * SYSTEM_STEP */
    double buffer[N_BUFFER];    /* every instance's outputs, as last read */
    size_t offsets[N_INSTANCES];
} Model;

#define ALIGN(n) (((n) + 15) / 16 * 16)

#define R(value) py_repr(value, (char[REPR_SIZE]){0})
#define MAX_SYSTEM_STEPS 10000000 /* per communication step, as the plant's RK4 sub-steps: doStep never hangs */

/* An inner model's messages go to the system's reporter, prefixed with the instance's name. */
typedef struct {
    const Reporter *outer;
    const char *name;
} Named;

static void named_log(void *host, ModelStatus status, const char *function, const char *message) {
    const Named *n = host;
    report(n->outer, status, "%s: %s", n->name, message);
    (void)function;
}

#define INNER(i, r)                                                                                  \
    Named named_ = {r, INSTANCES[i].name};                                                           \
    Reporter inner_ = {named_log, &named_, r ? r->function : ""};                                    \
    const Reporter *ir = r ? &inner_ : NULL

static void *block(Model *m, unsigned i) { return (char *)m + m->offsets[i]; }

static size_t system_size(const ModelType *type) {
    size_t size = ALIGN(sizeof(Model));
    for (unsigned i = 0; i < N_INSTANCES; i++) size += ALIGN(INSTANCES[i].type->size(INSTANCES[i].type));
    return size;
}

/* The system's values of one instance; ERROR when one is refused (reported where `r` is given). */
static ModelStatus apply_system_values(Model *m, unsigned i, const Reporter *r) {
    const InstanceRow *row = &INSTANCES[i];
    INNER(i, r);
    if (row->n_reals &&
        row->type->set_reals(row->type, block(m, i), row->real_vrs, row->n_reals, row->reals, 1, ir) > MODEL_WARNING)
        return MODEL_ERROR;
    if (row->n_strings && row->type->set_strings(row->type, block(m, i), row->string_vrs, row->n_strings,
                                                 row->strings, 1, ir) > MODEL_WARNING)
        return MODEL_ERROR;
    if (row->n_integers && row->type->set_integers(row->type, block(m, i), row->integer_vrs, row->n_integers,
                                                   row->integers, 1, ir) > MODEL_WARNING)
        return MODEL_ERROR;
    return MODEL_OK;
}

/* The start values: every instance's, then the system's values for it (a refused one is reported when
   initialisation ends, as the instances' own rules are). */
static ModelStatus system_instantiate(const ModelType *type, void *model, const Instantiation *at, const Reporter *r) {
    Model *m = model;
    for (unsigned i = 0; i < N_VARIABLES; i++) m->values[i] = VARIABLE_TABLE[i].start;
    size_t offset = ALIGN(sizeof(Model));
    for (unsigned i = 0; i < N_INSTANCES; i++) {
        m->offsets[i] = offset;
        offset += ALIGN(INSTANCES[i].type->size(INSTANCES[i].type));
        Instantiation inner = {INSTANCES[i].name, NULL, 0, 0}; /* co-simulation inside */
        INNER(i, r);
        ModelStatus status = INSTANCES[i].type->instantiate(INSTANCES[i].type, block(m, i), &inner, ir);
        if (status > MODEL_WARNING) return status;
        if (apply_system_values(m, i, NULL) != MODEL_OK && !m->bad_defaults) m->bad_defaults = (int)i + 1;
    }
    return MODEL_OK;
}

/* One exchange: every operation of EXCHANGE in order; the first status worse than a warning ends it. */
static ModelStatus exchange(Model *m, const Reporter *r) {
    for (unsigned k = 0; k < N_EXCHANGE; k++) {
        unsigned i = EXCHANGE[k].instance;
        const InstanceRow *row = &INSTANCES[i];
        INNER(i, r);
        ModelStatus status;
        if (EXCHANGE[k].operation == READ) {
            status = row->type->get_reals(row->type, block(m, i), row->outputs, row->n_outputs,
                                          &m->buffer[row->buffer], ir);
        } else {
            double values[MAX_INPUTS];
            for (unsigned j = 0; j < row->n_inputs; j++) values[j] = m->buffer[row->sources[j]];
            status = row->type->set_reals(row->type, block(m, i), row->inputs, row->n_inputs, values, !m->initialised, ir);
        }
        if (status > MODEL_WARNING) return status;
    }
    return MODEL_OK;
}

static ModelStatus system_exit_initialization(const ModelType *type, void *model, const Reporter *r) {
    Model *m = model;
    if (m->bad_defaults) { /* a system value was refused: say which, now that there is a reporter */
        apply_system_values(m, (unsigned)m->bad_defaults - 1, r);
        return MODEL_ERROR;
    }
    ModelStatus status = exchange(m, r); /* the master's initial exchange, in initialisation mode */
    for (unsigned i = 0; i < N_INSTANCES && status <= MODEL_WARNING; i++) {
        INNER(i, r);
        status = INSTANCES[i].type->exit_initialization(INSTANCES[i].type, block(m, i), ir);
    }
    if (status > MODEL_WARNING) return status;
    m->initialised = 1;
    return exchange(m, r); /* the outputs at the start time */
}

static ModelStatus system_set_reals(const ModelType *type, void *model, const unsigned vr[], size_t n,
                                    const double values[], int fixed_allowed, const Reporter *r) {
    Model *m = model;
    ModelStatus status = store_reals(MODEL_IDENTIFIER, VARIABLE_TABLE, N_VARIABLES, m->values, vr, n, values,
                                     fixed_allowed, r);
    for (size_t k = 0; k < n && status <= MODEL_WARNING; k++)
        for (unsigned j = 0; j < N_LINKS && status <= MODEL_WARNING; j++)
            if (LINKS[j].vr == vr[k]) {
                unsigned i = LINKS[j].instance;
                INNER(i, r);
                status = INSTANCES[i].type->set_reals(INSTANCES[i].type, block(m, i), &LINKS[j].target, 1, &values[k],
                                                      fixed_allowed, ir);
            }
    return status;
}

static ModelStatus system_get_reals(const ModelType *type, void *model, const unsigned vr[], size_t n,
                                    double values[], const Reporter *r) {
    Model *m = model;
    int read = m->initialised; /* before initialisation ends the outputs follow the parameters */
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= N_VARIABLES)
            return report(r, MODEL_ERROR, "%s has no variable with value reference %u", MODEL_IDENTIFIER, vr[k]);
        if (VARIABLE_TABLE[vr[k]].causality != OUTPUT) {
            values[k] = m->values[vr[k]];
            continue;
        }
        if (!read) {
            ModelStatus status = exchange(m, r);
            if (status > MODEL_WARNING) return status;
            read = 1;
        }
        for (unsigned j = 0; j < N_LINKS; j++)
            if (LINKS[j].vr == vr[k]) values[k] = m->buffer[LINKS[j].target];
    }
    return MODEL_OK;
}

/* How far a communication step may lie from a whole number n >= 0 of system steps, in system steps, to be taken
   as n: a host's rounding. Hosts that add up their steps (OMSimulator, a loop of t += h) end a run with the
   remainder stop - t, the sum's rounding: 1.03e-13 s after 10,000 steps of 1 ms (1.0e-10 system steps), 1.1e-10 s
   after 10^5 (1.1e-7). A remainder within it is n = 0: nothing to step. Any other step is refused. */
#define STEP_ROUNDING 1e-6

/* A communication step of any whole number of system steps: at each, the exchange, then every instance steps
   (in dependency order); after the last, the exchange that gives the outputs at the new time. */
static ModelStatus system_do_step(const ModelType *type, void *model, double time, double step, const Reporter *r) {
    Model *m = model;
    double n_steps = nearbyint(step / SYSTEM_STEP);
    if (fabs(step / SYSTEM_STEP - n_steps) > STEP_ROUNDING)
        return report(r, MODEL_ERROR, "communication step %s s must be a whole multiple of the system step %s s",
                      R(step), R(SYSTEM_STEP));
    if (n_steps > MAX_SYSTEM_STEPS)
        return report(r, MODEL_ERROR, "communication step %s s needs more than %d system steps of %s s", R(step),
                      MAX_SYSTEM_STEPS, R(SYSTEM_STEP));
    if (!m->started) m->start = time, m->started = 1;
    double first = nearbyint((time - m->start) / SYSTEM_STEP); /* time as the master's: start + k * step */
    ModelStatus worst = MODEL_OK;
    for (double k = first; k < first + n_steps; k++) {
        double t = m->start + k * SYSTEM_STEP;
        ModelStatus status = exchange(m, r);
        for (unsigned s = 0; s < N_INSTANCES && status <= MODEL_WARNING; s++) {
            unsigned i = STEP_ORDER[s];
            INNER(i, r);
            ModelStatus stepped = INSTANCES[i].type->do_step(INSTANCES[i].type, block(m, i), t, SYSTEM_STEP, ir);
            status = stepped > status ? stepped : status;
        }
        if (status > MODEL_WARNING) return status;
        if (status > worst) worst = status;
    }
    ModelStatus status = exchange(m, r);
    return status > worst ? status : worst;
}

const ModelType MODEL_TYPE = {.identifier = MODEL_IDENTIFIER,
                              .token = INSTANTIATION_TOKEN,
                              .size = system_size,
                              .instantiate = system_instantiate,
                              .exit_initialization = system_exit_initialization,
                              .get_reals = system_get_reals,
                              .set_reals = system_set_reals,
                              .do_step = system_do_step};
