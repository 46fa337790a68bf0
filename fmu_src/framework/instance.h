/*
 * What the FMI 2.0 and 3.0 frameworks share: one instance over one model (model.h), its state machine as bit
 * masks (the modes of co-simulation without event mode, FMI 2.0 section 4.2.4 and FMI 3.0 section 4.2), the
 * argument checks, the FMU states it made (any other pointer refused) and the log. No globals: any number of
 * instances, in any threads (one instance is called from one thread at a time, as FMI requires).
 */
#ifndef INSTANCE_H
#define INSTANCE_H

#include <stddef.h>

#include "model.h"

/* The modes; after an error the instance is FAILED until it is reset or a saved state is set back. Model Exchange
   has EVENT_MODE and CONTINUOUS_TIME where co-simulation has STEPPING and STEP_DISCARDED. */
enum { INSTANTIATED = 1, INITIALIZATION = 2, STEPPING = 4, STEP_DISCARDED = 8, TERMINATED = 16, FAILED = 32,
       EVENT_MODE = 64, CONTINUOUS_TIME = 128 };
#define RUNNING (STEPPING | STEP_DISCARDED | EVENT_MODE | CONTINUOUS_TIME)
#define ANY_MODE (INSTANTIATED | INITIALIZATION | TERMINATED | FAILED | RUNNING)
#define GETTABLE (INITIALIZATION | TERMINATED | FAILED | RUNNING)
#define SETTABLE (INSTANTIATED | INITIALIZATION | STEPPING | EVENT_MODE | CONTINUOUS_TIME)

struct Instance;
/* Passes one message to the host's logger (each FMI version has its own signature). */
typedef void (*HostLog)(struct Instance *c, ModelStatus status, const char *category, const char *message);

typedef struct SavedState SavedState;

typedef struct Instance {
    char *name;
    int mode, logging_on;
    double time;                 /* the last successful communication point */
    const ModelType *type;
    void *model;                 /* type->size(type) bytes */
    Instantiation at;            /* kept for a reset */
    SavedState **states;         /* the FMU states this instance made and has not freed */
    size_t n_states, states_size;
    const char *const *mode_names;
    HostLog host_log;
    void *host;                  /* the version's callbacks, kept by its framework */
    int model_exchange;          /* the host integrates the model (model.h's ContinuousModel) */
} Instance;

/* A new instance of the model `type`, instantiated; NULL (logged through `host_log`, which gets a bare instance
   then) if that fails. `location` is the resources' URI (FMI 2.0) or path (FMI 3.0), or NULL. `mode_names`
   names the modes in the order of their bits. */
int token_differs(const ModelType *type, const char *token, const char *location);
Instance *instance_new(const char *function, const ModelType *type, const char *name, const char *location,
                       int visible, int logging_on, const char *const *mode_names, HostLog host_log, void *host);
/* The same for Model Exchange (type->continuous not NULL): the instance goes to event mode, not step mode. */
Instance *instance_new_model_exchange(const char *function, const ModelType *type, const char *name,
                                      const char *location, int visible, int logging_on,
                                      const char *const *mode_names, HostLog host_log, void *host);
/* What a model call reports through: the instance's log, with the FMI function's name. */
Reporter instance_reporter(Instance *c, const char *function);
void instance_free(Instance *c);
/* Logs a message, an error's with the FMI function's name first ("fmi2DoStep: ..."); returns `status`. */
int instance_log(Instance *c, ModelStatus status, const char *function, const char *message);
/* May `function` be called in the instance's mode? If not, it logs why. */
int allowed(Instance *c, const char *function, int modes);
/* A refused call (bad arguments): an error and the reason, the mode unchanged. */
int refuse(Instance *c, const char *function, const char *why);
int set_logging(Instance *c, const char *function, int on);

int setup_experiment(Instance *c, const char *function, const Experiment *e);
int enter_initialization(Instance *c, const char *function);
int exit_initialization(Instance *c, const char *function);
int terminate(Instance *c, const char *function);
int reset(Instance *c, const char *function);
int get_reals(Instance *c, const char *function, const unsigned vr[], size_t n, double v[]);
int set_reals(Instance *c, const char *function, const unsigned vr[], size_t n, const double v[]);
int get_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *v[]);
int set_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *const v[]);
/* Values of a type this FMU has none of: only an empty call succeeds. */
/* Enumerations by their items' values (model.h's get_integers, set_integers). */
int get_integers(Instance *c, const char *function, const unsigned vr[], size_t n, long long v[]);
int set_integers(Instance *c, const char *function, const unsigned vr[], size_t n, const long long v[]);
int no_such_values(Instance *c, const char *function, int modes, size_t n);
int do_step(Instance *c, const char *function, double t, double h);

int get_fmu_state(Instance *c, const char *function, void **state);
int set_fmu_state(Instance *c, const char *function, void *state);
int free_fmu_state(Instance *c, const char *function, void **state);
int serialized_size(Instance *c, const char *function, void *state, size_t *size);
int serialize_fmu_state(Instance *c, const char *function, void *state, unsigned char out[], size_t size);
int deserialize_fmu_state(Instance *c, const char *function, const unsigned char data[], size_t size, void **state);

#endif
