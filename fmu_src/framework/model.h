/*
 * The model interface: what the FMI frameworks (fmi2Functions.c, fmi3Functions.c over instance.c) need from
 * a model, whoever answers it: a native component (models/component.c over one model file), a component's
 * Python runtime (python/python_model.c) or a system of native components (system/system.c). Reference-FMUs'
 * cut, with one difference: the model is reached through a ModelType, a table of functions, so that one
 * library can hold several models (a system) and the frameworks name none of them.
 *
 * A model is one block of type->size(type) bytes, zeroed before instantiate(), owned by the instance. Value
 * references are the FMI 2.0 ones, the positions in the model's variable table (the FMI 3.0 framework maps its
 * own, one higher: 0 is the independent variable time, which the framework answers itself).
 *
 * Model Exchange: a model that a host integrates has a ContinuousModel (`continuous`, NULL for co-simulation
 * only): its continuous states, their derivatives, event indicators, event updates and directional derivatives.
 * The frameworks offer the Model Exchange modes (event mode, continuous-time mode) where it is not NULL.
 */
#ifndef MODEL_H
#define MODEL_H

#include <stddef.h>

/* The statuses, with FMI's numbers (the same in 2.0 and 3.0). */
typedef enum { MODEL_OK = 0, MODEL_WARNING = 1, MODEL_DISCARD = 2, MODEL_ERROR = 3 } ModelStatus;

/* Where a model's messages go: the framework's logger, which puts the FMI function's name before an error's. */
typedef struct {
    void (*log)(void *host, ModelStatus status, const char *function, const char *message);
    void *host;
    const char *function; /* the FMI function being called, e.g. "fmi2DoStep" */
} Reporter;

/* Pass one message (printf-style) to the reporter (NULL: no message); returns `status`. */
ModelStatus report(const Reporter *r, ModelStatus status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* What a model is told when it is instantiated (and again when it is reset). */
typedef struct {
    const char *instance_name;
    const char *resources; /* the FMU's resources folder as a path, or NULL if the host gave none */
    int visible;
    int model_exchange; /* the host integrates the model (ModelType.continuous), no do_step */
} Instantiation;

/* What fmi2SetupExperiment (fmi3EnterInitializationMode) gives. */
typedef struct {
    double start, stop, tolerance;
    int stop_defined, tolerance_defined;
} Experiment;

typedef struct ModelType ModelType;

/* FMU states of a model that is not plain data (a ModelType with states = NULL is: the instance copies its block).
   `saved` is the model's own object; the instance keeps it with its mode and time. */
typedef struct {
    /* Save the model into *saved: a new object if *saved is NULL, else the one given, overwritten. */
    ModelStatus (*save)(const ModelType *type, void *m, void **saved, const Reporter *r);
    ModelStatus (*restore)(const ModelType *type, void *m, const void *saved, const Reporter *r);
    void (*discard)(const ModelType *type, void *saved);
    /* The bytes of a saved state (allocated with malloc, freed by the caller), and a saved state from bytes. */
    ModelStatus (*serialize)(const ModelType *type, void *m, const void *saved, unsigned char **bytes, size_t *size,
                             const Reporter *r);
    ModelStatus (*deserialize)(const ModelType *type, void *m, const unsigned char bytes[], size_t size, void **saved,
                               const Reporter *r);
} StateFunctions;

/* What a host that integrates a model calls (Model Exchange), each function like those of ModelType. */
typedef struct {
    size_t n_states, n_indicators;
    ModelStatus (*get_states)(const ModelType *type, void *m, double x[], const Reporter *r);
    ModelStatus (*set_states)(const ModelType *type, void *m, const double x[], const Reporter *r);
    ModelStatus (*derivatives)(const ModelType *type, void *m, double dx[], const Reporter *r);
    ModelStatus (*indicators)(const ModelType *type, void *m, double z[], const Reporter *r);
    /* The event update at `time` (also the first one, after initialisation); *terminate: the simulation ends. */
    ModelStatus (*event_update)(const ModelType *type, void *m, double time, int *terminate, const Reporter *r);
    /* sensitivity[i] = sum over j of d unknowns[i] / d knowns[j] * seed[j] (value references as get_reals'). */
    ModelStatus (*directional)(const ModelType *type, void *m, const unsigned unknowns[], size_t nu,
                               const unsigned knowns[], size_t nk, const double seed[], double sensitivity[],
                               const Reporter *r);
} ContinuousModel;

/* A model: its identity and its functions. Every function gets its type first, then the model's block; a
   function left NULL where it says so does nothing (or, for the String functions, means no String variables). */
struct ModelType {
    const char *identifier; /* the model identifier */
    const char *token;      /* the GUID / instantiation token of modelDescription.xml; NULL: any is accepted */
    const void *kind;       /* what the functions work from: a Component, a System (their own files say) */
    size_t (*size)(const ModelType *type);
    /* The start values (also at a reset, after free()); what the model needs from `at`. */
    ModelStatus (*instantiate)(const ModelType *type, void *m, const Instantiation *at, const Reporter *r);
    void (*free)(const ModelType *type, void *m); /* may be NULL */
    ModelStatus (*setup_experiment)(const ModelType *type, void *m, const Experiment *e, const Reporter *r); /* NULL */
    ModelStatus (*enter_initialization)(const ModelType *type, void *m, const Reporter *r);                /* NULL */
    /* End of initialisation: validate the parameters, set the initial state. */
    ModelStatus (*exit_initialization)(const ModelType *type, void *m, const Reporter *r);
    ModelStatus (*terminate)(const ModelType *type, void *m, const Reporter *r); /* may be NULL */
    /* Get n Reals (outputs before initialisation ends follow the parameters); set n Reals, all or none
       (`fixed_allowed`: initialisation has not ended, parameters may change). */
    ModelStatus (*get_reals)(const ModelType *type, void *m, const unsigned vr[], size_t n, double v[],
                             const Reporter *r);
    ModelStatus (*set_reals)(const ModelType *type, void *m, const unsigned vr[], size_t n, const double v[],
                             int fixed_allowed, const Reporter *r);
    /* Strings: valid until the next call on the instance; set ones are copied. NULL: the model has none. */
    ModelStatus (*get_strings)(const ModelType *type, void *m, const unsigned vr[], size_t n, const char *v[],
                               const Reporter *r);
    ModelStatus (*set_strings)(const ModelType *type, void *m, const unsigned vr[], size_t n, const char *const v[],
                               int fixed_allowed, const Reporter *r);
    /* Enumerations, by their items' values (FMI 2.0 fmi2GetInteger/fmi2SetInteger, FMI 3.0 fmi3GetInt64/fmi3SetInt64),
       like the Strings. NULL: the model has none. */
    ModelStatus (*get_integers)(const ModelType *type, void *m, const unsigned vr[], size_t n, long long v[],
                                const Reporter *r);
    ModelStatus (*set_integers)(const ModelType *type, void *m, const unsigned vr[], size_t n, const long long v[],
                                int fixed_allowed, const Reporter *r);
    /* One communication step from `time` of length `step` (> 0 and finite: the framework checks it). */
    ModelStatus (*do_step)(const ModelType *type, void *m, double time, double step, const Reporter *r);
    const StateFunctions *states; /* NULL: the model is plain data */
    const ContinuousModel *continuous; /* NULL: co-simulation only */
};

/* The model of this FMU, defined once per library (a generated fmu_model.c, or python_model.c). */
extern const ModelType *const FMU_MODEL;

#endif
