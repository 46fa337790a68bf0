/*
 * A native component: the C twin of crane_fmu/model/component.py's Component. A model file holds only the
 * component's equations and the rules that need a computation, as plain functions of the values by value
 * reference, its configuration and its state:
 *
 *   typedef struct { ... } Config;                 what configure() makes of the parameters
 *   typedef struct { ... } State;                  a component with a state only
 *   static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r);
 *   static void initial_state(const double values[], const Config *c, State *s);                        (state)
 *   static ModelStatus outputs(const double values[], const Config *c, [const State *s,] double out[],
 *                              const Reporter *r);  every output, in table order
 *   static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
 *                             const Reporter *r);   one communication step                                (state)
 *
 * and one registration, STATELESS_COMPONENT or STATEFUL_COMPONENT, which makes it a model (model.h) named
 * <ModelIdentifier>_MODEL. Everything else a model does (start values, gets and sets with their checks and
 * messages, outputs before initialisation following the parameters, FMU states) is component.c's, from the
 * variable table that `crane-fmu build` generates into <ModelIdentifier>_variables.h from the component's table.
 * That header also holds parameter_rules(), the component's declared parameter rules (its RULES), which the
 * registration runs before configure(): configure() sees only values that meet them.
 */
#ifndef COMPONENT_H
#define COMPONENT_H

#include <stddef.h>

#include "model.h"

/* The rows of a generated variable table. */
typedef enum { PARAMETER, INPUT, OUTPUT } Causality;
/* An ENUMERATION parameter is kept like a String, by its item's name (what configure() and the rules read), and
   exchanged with a host as the item's value: its position in `items` plus one. */
typedef enum { REAL, STRING, ENUMERATION } VariableType;
typedef struct {
    const char *name;
    Causality causality;
    VariableType type;
    double start;     /* a Real's */
    const char *text; /* a String's or an Enumeration's start value */
    const char *const *items; /* an Enumeration's item names, in the order of their values 1, 2, ... */
    unsigned n_items;
} VariableRow;

#define STRING_SIZE 256 /* the longest String value kept, with its terminating zero */
typedef char StringValue[STRING_SIZE];

/* A component that a host can integrate (Model Exchange): its continuous state is part of its State, and its
   Model Exchange variables (states that are no output, derivatives, event indicators) follow the table, value
   references n_variables... (the generated STATE_VRS, DERIVATIVE_VRS and INDICATOR_VRS say which is which). The
   inputs are the table's n_inputs rows from first_input; seeds are NULL where there is no direction. The outputs
   are Model Exchange's (model_exchange 1) or co-simulation's at a communication point (0: an output it keeps over
   a step, such as the acceleration over the last step, is that stored value there, and constant). */
typedef struct {
    unsigned n_states, n_indicators, n_locals, first_input, n_inputs;
    const unsigned *state_vrs, *derivative_vrs, *indicator_vrs;
    double *(*states)(void *state); /* where the continuous state lies in the State */
    ModelStatus (*derivatives)(const double values[], const void *config, const void *state, const double *ds,
                               const double *din, double f[], double *df, const Reporter *r);
    void (*outputs)(const double values[], const void *config, const void *state, int model_exchange,
                    const double *ds, const double *din, double out[], double *dout);
    void (*indicators)(const double values[], const void *config, const void *state, double z[]);
    ModelStatus (*event_update)(const double values[], const void *config, void *state, double time, int *terminate,
                                const Reporter *r);
} ContinuousComponent;

typedef struct {
    const VariableRow *variables;
    unsigned n_variables, first_output, n_outputs, n_strings; /* the outputs are the table's last rows */
    size_t config_size, state_size;
    ModelStatus (*configure)(const double values[], const StringValue strings[], void *config, const Reporter *r);
    void (*initial_state)(const double values[], const void *config, void *state); /* NULL: no state */
    ModelStatus (*outputs)(const double values[], const void *config, const void *state, double out[],
                           const Reporter *r);
    ModelStatus (*update)(const double values[], const void *config, void *state, double time, double step,
                          const Reporter *r); /* NULL: no state */
    const ContinuousComponent *continuous; /* NULL: co-simulation only */
} Component;

/* The model functions of every component (component.c). */
size_t component_size(const ModelType *type);
ModelStatus component_instantiate(const ModelType *type, void *m, const Instantiation *at, const Reporter *r);
ModelStatus component_exit_initialization(const ModelType *type, void *m, const Reporter *r);
ModelStatus component_get_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, double v[],
                                 const Reporter *r);
ModelStatus component_set_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, const double v[],
                                 int fixed_allowed, const Reporter *r);
ModelStatus component_get_strings(const ModelType *type, void *m, const unsigned vr[], size_t n, const char *v[],
                                  const Reporter *r);
ModelStatus component_set_strings(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                  const char *const v[], int fixed_allowed, const Reporter *r);
ModelStatus component_get_integers(const ModelType *type, void *m, const unsigned vr[], size_t n, long long v[],
                                   const Reporter *r);
ModelStatus component_set_integers(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                   const long long v[], int fixed_allowed, const Reporter *r);
ModelStatus component_do_step(const ModelType *type, void *m, double time, double step, const Reporter *r);
/* The Model Exchange functions (model.h's ContinuousModel) of a component with a ContinuousComponent. */
ModelStatus component_get_states(const ModelType *type, void *m, double x[], const Reporter *r);
ModelStatus component_set_states(const ModelType *type, void *m, const double x[], const Reporter *r);
ModelStatus component_derivatives(const ModelType *type, void *m, double dx[], const Reporter *r);
ModelStatus component_indicators(const ModelType *type, void *m, double z[], const Reporter *r);
ModelStatus component_event_update(const ModelType *type, void *m, double time, int *terminate, const Reporter *r);
ModelStatus component_directional(const ModelType *type, void *m, const unsigned unknowns[], size_t nu,
                                  const unsigned knowns[], size_t nk, const double seed[], double sensitivity[],
                                  const Reporter *r);

/* Check n Reals to set against a variable table (`model` names it in messages), all before any is stored in
   `store` (by value reference), and store them. */
ModelStatus store_reals(const char *model, const VariableRow table[], unsigned n_variables, double store[],
                        const unsigned vr[], size_t n, const double values[], int fixed_allowed, const Reporter *r);

/* The State, initial_state() and update() of a component whose state is only the time its outputs are for: 0 at
   first, then the end of the last step (the Python components' (0.0,) and (time + step,)). After Config. */
#define STATE_IS_TIME                                                                                        \
    typedef struct {                                                                                         \
        double time;                                                                                         \
    } State;                                                                                                 \
    static void initial_state(const double values[], const Config *c, State *s) { s->time = 0.0; }           \
    static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,    \
                              const Reporter *r) {                                                           \
        s->time = time + step;                                                                               \
        return MODEL_OK;                                                                                     \
    }

/* The model of a component, from the generated header's names (MODEL_TYPE is <ModelIdentifier>_MODEL). */
#define COMPONENT_MODEL_(component) COMPONENT_MODEL_WITH_(component, NULL)
#define COMPONENT_MODEL_WITH_(component, continuous_model)                                                   \
    const ModelType MODEL_TYPE = {.identifier = MODEL_IDENTIFIER,                                            \
                                  .token = INSTANTIATION_TOKEN,                                              \
                                  .kind = &component,                                                        \
                                  .size = component_size,                                                    \
                                  .instantiate = component_instantiate,                                      \
                                  .exit_initialization = component_exit_initialization,                      \
                                  .get_reals = component_get_reals,                                          \
                                  .set_reals = component_set_reals,                                          \
                                  .get_strings = N_STRINGS ? component_get_strings : NULL,                   \
                                  .set_strings = N_STRINGS ? component_set_strings : NULL,                   \
                                  .get_integers = N_ENUMERATIONS ? component_get_integers : NULL,            \
                                  .set_integers = N_ENUMERATIONS ? component_set_integers : NULL,            \
                                  .do_step = component_do_step,                                              \
                                  .continuous = continuous_model}

/* The registration of a model file whose component has no state: Config, configure() and outputs(). */
#define STATELESS_COMPONENT                                                                                  \
    static ModelStatus configure_(const double v[], const StringValue s[], void *c, const Reporter *r) {      \
        ModelStatus status = parameter_rules(v, s, r); /* the generated header's: the declared rules first */ \
        return status != MODEL_OK ? status : configure(v, s, c, r);                                          \
    }                                                                                                        \
    static ModelStatus outputs_(const double v[], const void *c, const void *s, double out[],                \
                                const Reporter *r) {                                                         \
        (void)s;                                                                                             \
        return outputs(v, c, out, r);                                                                        \
    }                                                                                                        \
    static const Component COMPONENT_ = {VARIABLE_TABLE, N_VARIABLES, FIRST_OUTPUT, N_OUTPUTS, N_STRINGS,    \
                                         sizeof(Config), 0, configure_, NULL, outputs_, NULL, NULL};         \
    COMPONENT_MODEL_(COMPONENT_)

/* The functions of a component with a state, typed for the model file's Config and State. */
#define STATEFUL_FUNCTIONS_                                                                                  \
    static ModelStatus configure_(const double v[], const StringValue s[], void *c, const Reporter *r) {      \
        ModelStatus status = parameter_rules(v, s, r); /* the generated header's: the declared rules first */ \
        return status != MODEL_OK ? status : configure(v, s, c, r);                                          \
    }                                                                                                        \
    static void initial_state_(const double v[], const void *c, void *s) { initial_state(v, c, s); }         \
    static ModelStatus outputs_(const double v[], const void *c, const void *s, double out[],                \
                                const Reporter *r) {                                                         \
        return outputs(v, c, s, out, r);                                                                     \
    }                                                                                                        \
    static ModelStatus update_(const double v[], const void *c, void *s, double t, double h,                 \
                               const Reporter *r) {                                                          \
        return update(v, c, s, t, h, r);                                                                     \
    }

/* The registration of a model file whose component has a state: Config, State, configure(), initial_state(),
   outputs() and update(). */
#define STATEFUL_COMPONENT                                                                                   \
    STATEFUL_FUNCTIONS_                                                                                      \
    static const Component COMPONENT_ = {VARIABLE_TABLE, N_VARIABLES, FIRST_OUTPUT, N_OUTPUTS, N_STRINGS,    \
                                         sizeof(Config), sizeof(State), configure_, initial_state_, outputs_, \
                                         update_, NULL};                                                     \
    COMPONENT_MODEL_(COMPONENT_)

/* The registration of a model file whose component a host can also integrate: besides STATEFUL_COMPONENT's,
   continuous_states(), derivatives(), continuous_outputs(), indicators() and event_update() (ContinuousComponent's
   functions, typed for the Config and State); the generated header's Model Exchange variables. */
#define CONTINUOUS_COMPONENT                                                                                 \
    STATEFUL_FUNCTIONS_                                                                                      \
    static double *states_(void *s) { return continuous_states(s); }                                        \
    static ModelStatus derivatives_(const double v[], const void *c, const void *s, const double *ds,        \
                                    const double *din, double f[], double *df, const Reporter *r) {          \
        return derivatives(v, c, s, ds, din, f, df, r);                                                      \
    }                                                                                                        \
    static void continuous_outputs_(const double v[], const void *c, const void *s, int me,                 \
                                    const double *ds, const double *din, double out[], double *dout) {       \
        continuous_outputs(v, c, s, me, ds, din, out, dout);                                                 \
    }                                                                                                        \
    static void indicators_(const double v[], const void *c, const void *s, double z[]) {                    \
        indicators(v, c, s, z);                                                                              \
    }                                                                                                        \
    static ModelStatus event_update_(const double v[], const void *c, void *s, double t, int *terminate,      \
                                     const Reporter *r) {                                                    \
        return event_update(v, c, s, t, terminate, r);                                                       \
    }                                                                                                        \
    static const ContinuousComponent CONTINUOUS_ = {                                                         \
        N_CONTINUOUS_STATES, N_EVENT_INDICATORS, N_LOCALS, FIRST_INPUT, N_INPUTS, STATE_VRS, DERIVATIVE_VRS,  \
        INDICATOR_VRS, states_, derivatives_, continuous_outputs_, indicators_, event_update_};              \
    static const Component COMPONENT_ = {VARIABLE_TABLE, N_VARIABLES, FIRST_OUTPUT, N_OUTPUTS, N_STRINGS,    \
                                         sizeof(Config), sizeof(State), configure_, initial_state_, outputs_, \
                                         update_, &CONTINUOUS_};                                             \
    static const ContinuousModel CONTINUOUS_MODEL_ = {                                                       \
        N_CONTINUOUS_STATES, N_EVENT_INDICATORS, component_get_states, component_set_states,                 \
        component_derivatives, component_indicators, component_event_update, component_directional};        \
    COMPONENT_MODEL_WITH_(COMPONENT_, &CONTINUOUS_MODEL_)

#endif
