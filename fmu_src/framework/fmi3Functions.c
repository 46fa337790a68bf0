/*
 * FMI 3.0 co-simulation, and Model Exchange for a model that has a ContinuousModel, over the model interface
 * (model.h) of this FMU's model (FMU_MODEL): the official fmi3Functions.h, each call mapped to instance.c (and
 * continuous.c). Value reference 0 is the independent variable `time`,
 * answered here; the model's variables follow from 1 (the FMI 2.0 value reference plus one).
 */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmi3_calls.h"
#include "continuous.h"
#include "instance.h"

static const char *const MODE_NAMES[] = {
    "instantiated", "in initialization mode", "in step mode", "in step mode after a discarded step", "terminated",
    "in error state (after an fmi3Error; fmi3Reset or fmi3SetFMUState recover it)", "in event mode",
    "in continuous-time mode"};

typedef struct {
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message;
} Host;

static void host_log(Instance *c, ModelStatus status, const char *category, const char *message) {
    const Host *h = c->host;
    if (h->log_message) h->log_message(h->environment, (fmi3Status)status, category, message);
}

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String name, fmi3String token, fmi3String resource_path, fmi3Boolean visible, fmi3Boolean logging_on,
    fmi3Boolean event_mode_used, fmi3Boolean early_return_allowed, const fmi3ValueReference required[],
    size_t n_required, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log_message,
    fmi3IntermediateUpdateCallback intermediate_update) {
    (void)early_return_allowed, (void)required, (void)n_required, (void)intermediate_update;
    if (!name) return NULL;
    Host *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    *h = (Host){environment, log_message};
    Instance bare = {.name = (char *)name, .logging_on = logging_on, .host = h}; /* logs before an instance exists */
    Instance *c = NULL;
    if (event_mode_used) {
        host_log(&bare, MODEL_ERROR, "logStatusError", "fmi3InstantiateCoSimulation: this FMU has no event mode");
    } else if (token_differs(FMU_MODEL, token, resource_path)) {
        host_log(&bare, MODEL_ERROR, "logStatusError",
                 "fmi3InstantiateCoSimulation: the instantiation token is not this FMU's");
    } else {
        c = instance_new("fmi3InstantiateCoSimulation", FMU_MODEL, name, resource_path, visible, logging_on,
                         MODE_NAMES, host_log, h);
    }
    if (!c) free(h);
    return c;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resource_path,
                                                      fmi3Boolean visible, fmi3Boolean logging_on,
                                                      fmi3InstanceEnvironment environment,
                                                      fmi3LogMessageCallback log_message) {
    if (!name) return NULL;
    if (!FMU_MODEL->continuous) {
        if (log_message) log_message(environment, fmi3Error, "logStatusError", "this FMU supports co-simulation only");
        return NULL;
    }
    Host *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    *h = (Host){environment, log_message};
    Instance bare = {.name = (char *)name, .logging_on = logging_on, .host = h}; /* logs before an instance exists */
    Instance *c = NULL;
    if (token_differs(FMU_MODEL, token, resource_path)) {
        host_log(&bare, MODEL_ERROR, "logStatusError",
                 "fmi3InstantiateModelExchange: the instantiation token is not this FMU's");
    } else {
        c = instance_new_model_exchange("fmi3InstantiateModelExchange", FMU_MODEL, name, resource_path, visible,
                                        logging_on, MODE_NAMES, host_log, h);
    }
    if (!c) free(h);
    return c;
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String name, fmi3String token, fmi3String resource_path, fmi3Boolean visible, fmi3Boolean logging_on,
    fmi3InstanceEnvironment environment, fmi3LogMessageCallback log_message, fmi3ClockUpdateCallback clock_update,
    fmi3LockPreemptionCallback lock, fmi3UnlockPreemptionCallback unlock) {
    (void)name, (void)token, (void)resource_path, (void)visible, (void)logging_on, (void)clock_update, (void)lock;
    (void)unlock;
    if (log_message) log_message(environment, fmi3Error, "logStatusError", "this FMU supports co-simulation only");
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance c) {
    if (!c) return;
    void *h = ((Instance *)c)->host;
    instance_free(c);
    free(h);
}

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[]) {
    (void)n, (void)cats;
    return set_logging(c, "fmi3SetDebugLogging", on);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    Experiment e = {start, stop, tolerance, stop_defined, tolerance_defined};
    int status = setup_experiment(c, "fmi3EnterInitializationMode", &e);
    return (fmi3Status)(status > MODEL_WARNING ? status : enter_initialization(c, "fmi3EnterInitializationMode"));
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance c) { return exit_initialization(c, "fmi3ExitInitializationMode"); }
fmi3Status fmi3Terminate(fmi3Instance c) { return terminate(c, "fmi3Terminate"); }
fmi3Status fmi3Reset(fmi3Instance c) { return reset(c, "fmi3Reset"); }

static const char *const TIME_NOT_SET = "time (value reference 0) is the independent variable: it is never set";
static const char *const TIME_NOT_STRING = "value reference 0 is time, a Float64";

#define SMALL 64 /* value references mapped on the stack; more take a checked allocation */

/* The model's value references (FMI 3.0's less one) into *mapped, and their count into *n_model; 0 with a
   logged error. Value reference 0 is `time`: with `time_refused` NULL it is skipped (the caller answers it),
   else refused with that text. */
static int map_vrs(Instance *c, const char *function, const fmi3ValueReference vr[], size_t n,
                   const char *time_refused, unsigned small[], unsigned **mapped, size_t *n_model) {
    *mapped = n <= SMALL ? small : malloc(n * sizeof **mapped);
    if (!*mapped) return refuse(c, function, "out of memory"), 0;
    *n_model = 0;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] == 0 && time_refused) {
            if (*mapped != small) free(*mapped);
            return refuse(c, function, time_refused), 0;
        }
        if (vr[i] != 0) (*mapped)[(*n_model)++] = vr[i] - 1;
    }
    return 1;
}

/* `time` is read with any other Float64 variables, as any host may ask (fmusim reads it with the outputs): the
   model's values fill the front of v, then spread out from the back to their places, time between them. */
fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 v[], size_t n) {
    if (!allowed(c, "fmi3GetFloat64", GETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3GetFloat64", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3GetFloat64", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3GetFloat64", vr, nvr, NULL, small, &mapped, &n_model)) return fmi3Error;
    fmi3Status status = n_model ? get_reals(c, "fmi3GetFloat64", mapped, n_model, v) : fmi3OK;
    if (mapped != small) free(mapped);
    if (status > fmi3Warning) return status;
    for (size_t i = nvr, j = n_model; i-- > 0;) v[i] = vr[i] == 0 ? ((Instance *)c)->time : v[--j];
    return status;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 v[], size_t n) {
    if (!allowed(c, "fmi3SetFloat64", SETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3SetFloat64", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3SetFloat64", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3SetFloat64", vr, nvr, TIME_NOT_SET, small, &mapped, &n_model)) return fmi3Error;
    fmi3Status status = set_reals(c, "fmi3SetFloat64", mapped, nvr, v);
    if (mapped != small) free(mapped);
    return status;
}

#define NO_GET(Type)                                                                                         \
    fmi3Status fmi3Get##Type(VRS_, fmi3##Type v[], size_t n) {                                               \
        (void)vr, (void)nvr, (void)v;                                                                        \
        return no_such_values(c, "fmi3Get" #Type, GETTABLE, n);                                              \
    }
#define NO_SET(Type)                                                                                         \
    fmi3Status fmi3Set##Type(VRS_, const fmi3##Type v[], size_t n) {                                         \
        (void)vr, (void)nvr, (void)v;                                                                        \
        return no_such_values(c, "fmi3Set" #Type, SETTABLE, n);                                              \
    }
/* The types no model here has a variable of: asking for no value is taken (nothing to do), any value refused. */
NO_GET(Int32) NO_GET(UInt64) NO_GET(Boolean) NO_GET(Float32) NO_GET(Int8) NO_GET(UInt8) NO_GET(Int16) NO_GET(UInt16)
NO_GET(UInt32)
NO_SET(Int32) NO_SET(UInt64) NO_SET(Boolean) NO_SET(Float32) NO_SET(Int8) NO_SET(UInt8) NO_SET(Int16) NO_SET(UInt16)
NO_SET(UInt32)

/* Enumerations (FMI 3.0 gets and sets them as Int64). */
static const char *const TIME_NOT_INT64 = "value reference 0 is time, a Float64";
fmi3Status fmi3GetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Int64 v[], size_t n) {
    if (!allowed(c, "fmi3GetInt64", GETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3GetInt64", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3GetInt64", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3GetInt64", vr, nvr, TIME_NOT_INT64, small, &mapped, &n_model)) return fmi3Error;
    long long *wide = malloc(nvr * sizeof *wide);
    fmi3Status status = wide ? get_integers(c, "fmi3GetInt64", mapped, nvr, wide) : refuse(c, "fmi3GetInt64", "out of memory");
    if (wide && status <= fmi3Warning)
        for (size_t i = 0; i < nvr; i++) v[i] = (fmi3Int64)wide[i];
    free(wide);
    if (mapped != small) free(mapped);
    return status;
}

fmi3Status fmi3SetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Int64 v[], size_t n) {
    if (!allowed(c, "fmi3SetInt64", SETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3SetInt64", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3SetInt64", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3SetInt64", vr, nvr, TIME_NOT_INT64, small, &mapped, &n_model)) return fmi3Error;
    long long *wide = malloc(nvr * sizeof *wide);
    for (size_t i = 0; wide && i < nvr; i++) wide[i] = v[i];
    fmi3Status status = wide ? set_integers(c, "fmi3SetInt64", mapped, nvr, wide) : refuse(c, "fmi3SetInt64", "out of memory");
    free(wide);
    if (mapped != small) free(mapped);
    return status;
}

fmi3Status fmi3GetString(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3String v[], size_t n) {
    if (!allowed(c, "fmi3GetString", GETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3GetString", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3GetString", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3GetString", vr, nvr, TIME_NOT_STRING, small, &mapped, &n_model)) return fmi3Error;
    fmi3Status status = get_strings(c, "fmi3GetString", mapped, nvr, v);
    if (mapped != small) free(mapped);
    return status;
}

fmi3Status fmi3SetString(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3String v[], size_t n) {
    if (!allowed(c, "fmi3SetString", SETTABLE)) return fmi3Error;
    if (n != nvr) return refuse(c, "fmi3SetString", "arrays are not supported (nValues != nValueReferences)");
    if (nvr == 0) return fmi3OK;
    if (!vr || !v) return refuse(c, "fmi3SetString", "NULL array");
    unsigned small[SMALL], *mapped;
    size_t n_model;
    if (!map_vrs(c, "fmi3SetString", vr, nvr, TIME_NOT_STRING, small, &mapped, &n_model)) return fmi3Error;
    fmi3Status status = set_strings(c, "fmi3SetString", mapped, nvr, v);
    if (mapped != small) free(mapped);
    return status;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior, fmi3Boolean *event_needed,
                      fmi3Boolean *terminate, fmi3Boolean *early_return, fmi3Float64 *last_time) {
    (void)no_prior;
    if (!event_needed || !terminate || !early_return || !last_time)
        return c ? refuse(c, "fmi3DoStep", "NULL output pointer") : fmi3Error;
    fmi3Status status = do_step(c, "fmi3DoStep", t, h);
    *event_needed = *terminate = *early_return = fmi3False;
    *last_time = c ? ((Instance *)c)->time : t;
    return status;
}

/* ---- Model Exchange (continuous.c) ---- */

fmi3Status fmi3EnterEventMode(fmi3Instance c) { return enter_event_mode(c, "fmi3EnterEventMode", CONTINUOUS_TIME); }
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) {
    return enter_continuous_time_mode(c, "fmi3EnterContinuousTimeMode");
}
fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) { return set_time(c, "fmi3SetTime", time); }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *update, fmi3Boolean *terminate,
                                    fmi3Boolean *nominals_changed, fmi3Boolean *values_changed,
                                    fmi3Boolean *next_defined, fmi3Float64 *next_time) {
    if (!update || !terminate || !nominals_changed || !values_changed || !next_defined || !next_time)
        return c ? refuse(c, "fmi3UpdateDiscreteStates", "NULL output pointer") : fmi3Error;
    int end = 0, changed = 0;
    fmi3Status status = update_discrete_states(c, "fmi3UpdateDiscreteStates", &end, &changed);
    *update = *nominals_changed = *next_defined = fmi3False;
    *terminate = end != 0, *values_changed = changed != 0, *next_time = 0.0;
    return status;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean no_prior, fmi3Boolean *event,
                                       fmi3Boolean *terminate) {
    (void)no_prior;
    int enter = 0, end = 0;
    fmi3Status status =
        completed_integrator_step(c, "fmi3CompletedIntegratorStep", event && terminate ? &enter : NULL, &end);
    if (event && terminate) *event = enter != 0, *terminate = end != 0;
    return status;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t n) {
    return set_continuous_states(c, "fmi3SetContinuousStates", x, n);
}
fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n) {
    return get_continuous_states(c, "fmi3GetContinuousStates", x, n);
}
/* FMI 3.0 section 2.3: the derivatives and the nominals from Initialization Mode on (Event, Continuous-Time Mode,
   Terminated, which an FMU enters after an error), not when instantiated. */
#define ME_FROM_INITIALIZATION (INITIALIZATION | EVENT_MODE | CONTINUOUS_TIME | TERMINATED | FAILED)
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t n) {
    return get_derivatives(c, "fmi3GetContinuousStateDerivatives", ME_FROM_INITIALIZATION, dx, n);
}
fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t n) {
    return get_event_indicators(c, "fmi3GetEventIndicators", z, n);
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n) {
    return get_nominals(c, "fmi3GetNominalsOfContinuousStates", ME_FROM_INITIALIZATION, x, n);
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) {
    if (!is_model_exchange(c, "fmi3GetNumberOfContinuousStates")) return fmi3Error;
    if (!n) return refuse(c, "fmi3GetNumberOfContinuousStates", "NULL pointer");
    *n = number_of_states(c);
    return fmi3OK;
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) {
    if (!is_model_exchange(c, "fmi3GetNumberOfEventIndicators")) return fmi3Error;
    if (!n) return refuse(c, "fmi3GetNumberOfEventIndicators", "NULL pointer");
    *n = number_of_indicators(c);
    return fmi3OK;
}

/* The directional or adjoint derivative with FMI 3.0's value references (time, 0, is neither known nor unknown). */
static fmi3Status derivative(fmi3Instance c, const char *function, int adjoint, const fmi3ValueReference unknowns[],
                             size_t nu, const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                             size_t ns, fmi3Float64 sensitivity[], size_t nsens) {
    if (!c) return fmi3Error;
    if (ns != (adjoint ? nu : nk) || nsens != (adjoint ? nk : nu))
        return refuse(c, function, "arrays are not supported (the seed and sensitivity lengths must match)");
    if ((nu && !unknowns) || (nk && !knowns)) return refuse(c, function, "NULL array");
    unsigned small_u[SMALL], small_k[SMALL], *u, *k;
    size_t n_u, n_k;
    static const char *const TIME = "time (value reference 0) has no derivatives here";
    if (!map_vrs(c, function, unknowns, nu, TIME, small_u, &u, &n_u)) return fmi3Error;
    fmi3Status status = fmi3Error;
    if (map_vrs(c, function, knowns, nk, TIME, small_k, &k, &n_k)) {
        status = (adjoint ? adjoint_derivative : directional_derivative)(c, function, u, nu, k, nk, seed, sensitivity);
        if (k != small_k) free(k);
    }
    if (u != small_u) free(u);
    return status;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nu,
                                        const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[],
                                        size_t ns, fmi3Float64 sensitivity[], size_t nsens) {
    return derivative(c, "fmi3GetDirectionalDerivative", 0, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens);
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nu,
                                    const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[], size_t ns,
                                    fmi3Float64 sensitivity[], size_t nsens) {
    return derivative(c, "fmi3GetAdjointDerivative", 1, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens);
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) { return get_fmu_state(c, "fmi3GetFMUState", s); }
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) { return set_fmu_state(c, "fmi3SetFMUState", s); }
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) { return free_fmu_state(c, "fmi3FreeFMUState", s); }
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *size) {
    return serialized_size(c, "fmi3SerializedFMUStateSize", s, size);
}
fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte out[], size_t size) {
    return serialize_fmu_state(c, "fmi3SerializeFMUState", s, out, size);
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte data[], size_t size, fmi3FMUState *s) {
    return deserialize_fmu_state(c, "fmi3DeserializeFMUState", data, size, s);
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        return c ? refuse(c, #name, "not supported by this FMU") : fmi3Error;                                \
    }
FMI3_OTHERS(UNSUPPORTED)
