/*
 * A system of native models as one model (system.c): what its generated system_config.h describes.
 * Each component model linked in is reached through a ModelApi; MODEL_API(Prefix_) declares the
 * renamed globals of a model file compiled with MODEL_PREFIX = Prefix_ (model.h) and makes its ModelApi.
 */
#ifndef SYSTEM_H
#define SYSTEM_H

#include "model.h"

typedef struct {
    void (*defaults)(void *m);
    ModelStatus (*set_reals)(void *m, const unsigned vr[], size_t n, const double v[], int fixed, const Reporter *r);
    ModelStatus (*get_reals)(void *m, const unsigned vr[], size_t n, double v[], const Reporter *r);
    ModelStatus (*set_strings)(void *m, const unsigned vr[], size_t n, const char *const v[], int fixed,
                               const Reporter *r);
    ModelStatus (*initialize)(void *m, const Reporter *r);
    ModelStatus (*do_step)(void *m, double time, double step, const Reporter *r);
} ModelApi;

#define MODEL_API(P)                                                                                              \
    struct P##Model;                                                                                              \
    void P##model_defaults(struct P##Model *m);                                                                   \
    ModelStatus P##model_set_reals(struct P##Model *m, const unsigned vr[], size_t n, const double v[], int fixed, \
                                   const Reporter *r);                                                            \
    ModelStatus P##model_get_reals(struct P##Model *m, const unsigned vr[], size_t n, double v[], const Reporter *r); \
    ModelStatus P##model_set_strings(struct P##Model *m, const unsigned vr[], size_t n, const char *const v[],     \
                                     int fixed, const Reporter *r);                                               \
    ModelStatus P##model_initialize(struct P##Model *m, const Reporter *r);                                       \
    ModelStatus P##model_do_step(struct P##Model *m, double time, double step, const Reporter *r);                \
    static void P##defaults(void *m) { P##model_defaults(m); }                                                    \
    static ModelStatus P##set_reals(void *m, const unsigned vr[], size_t n, const double v[], int fixed,           \
                                    const Reporter *r) {                                                          \
        return P##model_set_reals(m, vr, n, v, fixed, r);                                                         \
    }                                                                                                             \
    static ModelStatus P##get_reals(void *m, const unsigned vr[], size_t n, double v[], const Reporter *r) {      \
        return P##model_get_reals(m, vr, n, v, r);                                                                \
    }                                                                                                             \
    static ModelStatus P##set_strings(void *m, const unsigned vr[], size_t n, const char *const v[], int fixed,   \
                                      const Reporter *r) {                                                        \
        return P##model_set_strings(m, vr, n, v, fixed, r);                                                       \
    }                                                                                                             \
    static ModelStatus P##initialize(void *m, const Reporter *r) { return P##model_initialize(m, r); }            \
    static ModelStatus P##do_step(void *m, double time, double step, const Reporter *r) {                         \
        return P##model_do_step(m, time, step, r);                                                                \
    }                                                                                                             \
    static const ModelApi P##API = {P##defaults, P##set_reals, P##get_reals, P##set_strings, P##initialize,       \
                                    P##do_step};

/* One instance of a component model, and the system's data for it. */
typedef struct {
    const char *name;     /* the instance's name: its messages are prefixed with it */
    const ModelApi *api;
    size_t offset;        /* where its model lies in the system model's blocks (in doubles) */
    unsigned n_outputs;   /* every output, read into the buffer from `buffer` on */
    const unsigned *outputs;
    unsigned buffer;
    unsigned n_inputs;    /* the connected inputs and the buffer positions that feed them */
    const unsigned *inputs, *sources;
    unsigned n_reals;     /* the system's parameter values, set after the defaults */
    const unsigned *real_vrs;
    const double *reals;
    unsigned n_strings;
    const unsigned *string_vrs;
    const char *const *strings;
} InstanceRow;

/* The exchange in Gauss-Seidel order (crane_fmu.cosim.master.Wiring.propagation): read an instance's outputs
   or set its connected inputs. */
typedef enum { READ, WRITE } Operation;
typedef struct {
    Operation operation;
    unsigned instance;
} Exchange;

/* Where a variable of the system goes: a parameter or input to an instance's variable, an output from a
   buffer position. */
typedef struct {
    unsigned vr, instance, target;
} Link;

#endif
