/*
 * The model interface: what the FMI frameworks (fmi2_framework.c, fmi3_framework.c) need from one
 * component's model file (crane_plant.c), Reference-FMUs' shape. A model is plain data (no
 * pointers), so an FMU state is a copy of it. Value references are the FMI 2.0 ones: the
 * positions in the component's variable table (the FMI 3.0 framework maps its own, one higher).
 */
#ifndef MODEL_H
#define MODEL_H

#include <stddef.h>

/* Several model files in one library (a system as one FMU, build_scripts/one_fmu.py): a model file compiled
   with MODEL_PREFIX defined (e.g. CranePlant_) gets its globals renamed (CranePlant_model_defaults,
   CranePlant_MODEL_SIZE, struct CranePlant_Model, ...), so that they do not clash. Model files need no change. */
#ifdef MODEL_PREFIX
#define MODEL_PASTE_(prefix, name) prefix##name
#define MODEL_PASTE(prefix, name) MODEL_PASTE_(prefix, name)
#define Model MODEL_PASTE(MODEL_PREFIX, Model)
#define MODEL_NAME MODEL_PASTE(MODEL_PREFIX, MODEL_NAME)
#define MODEL_TOKEN MODEL_PASTE(MODEL_PREFIX, MODEL_TOKEN)
#define MODEL_SIZE MODEL_PASTE(MODEL_PREFIX, MODEL_SIZE)
#define MODEL_N_VARIABLES MODEL_PASTE(MODEL_PREFIX, MODEL_N_VARIABLES)
#define MODEL_N_STRINGS MODEL_PASTE(MODEL_PREFIX, MODEL_N_STRINGS)
#define model_defaults MODEL_PASTE(MODEL_PREFIX, model_defaults)
#define model_set_reals MODEL_PASTE(MODEL_PREFIX, model_set_reals)
#define model_get_reals MODEL_PASTE(MODEL_PREFIX, model_get_reals)
#define model_set_strings MODEL_PASTE(MODEL_PREFIX, model_set_strings)
#define model_get_strings MODEL_PASTE(MODEL_PREFIX, model_get_strings)
#define model_initialize MODEL_PASTE(MODEL_PREFIX, model_initialize)
#define model_do_step MODEL_PASTE(MODEL_PREFIX, model_do_step)
#endif

/* The statuses, with FMI's numbers (the same in 2.0 and 3.0). */
typedef enum { MODEL_OK = 0, MODEL_WARNING = 1, MODEL_DISCARD = 2, MODEL_ERROR = 3 } ModelStatus;

/* Where a model's messages go: the framework's logger, which prefixes the FMI function's name. */
typedef struct {
    void (*log)(void *host, ModelStatus status, const char *function, const char *message);
    void *host;
    const char *function; /* the FMI function being called, e.g. "fmi2DoStep" */
} Reporter;

/* Pass one message (printf-style) to the reporter; returns `status`. */
ModelStatus report(const Reporter *r, ModelStatus status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

typedef struct Model Model; /* defined by the model file */

extern const char *const MODEL_NAME; /* the model identifier */
extern const char *const MODEL_TOKEN; /* the GUID / instantiation token of modelDescription.xml */
extern const size_t MODEL_SIZE;       /* sizeof(Model) */
extern const unsigned MODEL_N_VARIABLES;
extern const unsigned MODEL_N_STRINGS; /* its String variables; none: the frameworks refuse String calls */

/* The start values: a model as instantiated (and after a reset). */
void model_defaults(Model *m);
/* Set n Reals, all or none; `fixed_allowed` is true before initialisation ends (parameters may change). */
ModelStatus model_set_reals(Model *m, const unsigned vr[], size_t n, const double values[], int fixed_allowed,
                            const Reporter *r);
/* Get n Reals (outputs before initialisation follow the parameters, validated). */
ModelStatus model_get_reals(Model *m, const unsigned vr[], size_t n, double values[], const Reporter *r);
/* Set n Strings (copied), all or none; get n Strings (valid until the next call on the instance). Called only when
   MODEL_N_STRINGS > 0. */
ModelStatus model_set_strings(Model *m, const unsigned vr[], size_t n, const char *const values[], int fixed_allowed,
                              const Reporter *r);
ModelStatus model_get_strings(Model *m, const unsigned vr[], size_t n, const char *values[], const Reporter *r);
/* End of initialisation: validate the parameters and set the initial state. */
ModelStatus model_initialize(Model *m, const Reporter *r);
/* One communication step from `time` of length `step` (> 0 and finite: the frameworks check it): OK (maybe with
   warnings logged), DISCARD, or ERROR. */
ModelStatus model_do_step(Model *m, double time, double step, const Reporter *r);

#endif
