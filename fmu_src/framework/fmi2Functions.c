/*
 * FMI 2.0 co-simulation, and Model Exchange for a model that has a ContinuousModel, over the model interface
 * (model.h) of this FMU's model (FMU_MODEL): the official fmi2Functions.h, each call mapped to instance.c (and
 * continuous.c). The functions this FMU does not support answer fmi2Error.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi2_calls.h"
#include "continuous.h"
#include "instance.h"

static const char *const MODE_NAMES[] = {
    "instantiated", "in initialization mode", "in step-complete state",
    "in step-failed state (its last step was discarded)", "terminated",
    "in error state (after an fmi2Error; fmi2Reset or fmi2SetFMUstate recover it)", "in event mode",
    "in continuous-time mode"};

typedef struct {
    fmi2CallbackFunctions cb;
} Host;

static void host_log(Instance *c, ModelStatus status, const char *category, const char *message) {
    const Host *h = c->host;
    if (h->cb.logger) h->cb.logger(h->cb.componentEnvironment, c->name, (fmi2Status)status, category, "%s", message);
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                          const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                          fmi2Boolean logging_on) {
    if (!functions || !name) return NULL;
    Host *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    h->cb = *functions;
    Instance bare = {.name = (char *)name, .logging_on = logging_on, .host = h}; /* logs before an instance exists */
    Instance *c = NULL;
    if (type != fmi2CoSimulation && !(type == fmi2ModelExchange && FMU_MODEL->continuous)) {
        host_log(&bare, MODEL_ERROR, "logStatusError", "fmi2Instantiate: this FMU supports co-simulation only");
    } else if (token_differs(FMU_MODEL, guid, location)) {
        host_log(&bare, MODEL_ERROR, "logStatusError",
                 "fmi2Instantiate: the GUID is not this FMU's (a modelDescription.xml of another build?)");
    } else {
        c = (type == fmi2ModelExchange ? instance_new_model_exchange : instance_new)(
            "fmi2Instantiate", FMU_MODEL, name, location, visible, logging_on, MODE_NAMES, host_log, h);
    }
    if (!c) free(h);
    return c;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    if (!c) return;
    void *h = ((Instance *)c)->host;
    instance_free(c);
    free(h);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)n, (void)cats;
    return set_logging(c, "fmi2SetDebugLogging", on);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    Experiment e = {start, stop, tolerance, stop_defined, tolerance_defined};
    return setup_experiment(c, "fmi2SetupExperiment", &e);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return enter_initialization(c, "fmi2EnterInitializationMode");
}
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return exit_initialization(c, "fmi2ExitInitializationMode"); }
fmi2Status fmi2Terminate(fmi2Component c) { return terminate(c, "fmi2Terminate"); }
fmi2Status fmi2Reset(fmi2Component c) { return reset(c, "fmi2Reset"); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    return get_reals(c, "fmi2GetReal", vr, n, v);
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    return set_reals(c, "fmi2SetReal", vr, n, v);
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    return get_strings(c, "fmi2GetString", vr, n, v);
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    return set_strings(c, "fmi2SetString", vr, n, v);
}

/* Enumerations (FMI 2.0 gets and sets them as Integers): through the model's long long values. */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    long long small[16], *wide = n <= 16 ? small : malloc(n * sizeof *wide);
    if (!wide) return c ? refuse(c, "fmi2GetInteger", "out of memory") : fmi2Error;
    fmi2Status status = get_integers(c, "fmi2GetInteger", vr, n, v ? wide : NULL); /* NULL values: refused */
    if (status <= fmi2Warning && v)
        for (size_t i = 0; i < n; i++) v[i] = (fmi2Integer)wide[i];
    if (wide != small) free(wide);
    return status;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    long long small[16], *wide = n <= 16 ? small : malloc(n * sizeof *wide);
    if (!wide) return c ? refuse(c, "fmi2SetInteger", "out of memory") : fmi2Error;
    for (size_t i = 0; v && i < n; i++) wide[i] = v[i];
    fmi2Status status = set_integers(c, "fmi2SetInteger", vr, n, v ? wide : NULL);
    if (wide != small) free(wide);
    return status;
}

#define NO_VALUES(Name, modes, ctype)                                                                        \
    fmi2Status Name(fmi2Component c, const fmi2ValueReference vr[], size_t n, ctype v[]) {                   \
        (void)vr, (void)v;                                                                                   \
        return no_such_values(c, #Name, modes, n);                                                           \
    }
NO_VALUES(fmi2GetBoolean, GETTABLE, fmi2Boolean)
NO_VALUES(fmi2SetBoolean, SETTABLE, const fmi2Boolean)

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    return do_step(c, "fmi2DoStep", t, h);
}

/* ---- Model Exchange (continuous.c) ---- */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    return enter_event_mode(c, "fmi2EnterEventMode", EVENT_MODE | CONTINUOUS_TIME);
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    return enter_continuous_time_mode(c, "fmi2EnterContinuousTimeMode");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { return set_time(c, "fmi2SetTime", time); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    if (!info) return c ? refuse(c, "fmi2NewDiscreteStates", "NULL event info") : fmi2Error;
    int terminate = 0, changed = 0;
    fmi2Status status = update_discrete_states(c, "fmi2NewDiscreteStates", &terminate, &changed);
    *info = (fmi2EventInfo){.newDiscreteStatesNeeded = fmi2False, .terminateSimulation = terminate != 0,
                            .nominalsOfContinuousStatesChanged = fmi2False,
                            .valuesOfContinuousStatesChanged = changed != 0, .nextEventTimeDefined = fmi2False};
    return status;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean no_prior, fmi2Boolean *event,
                                       fmi2Boolean *terminate) {
    (void)no_prior;
    int enter = 0, end = 0;
    fmi2Status status =
        completed_integrator_step(c, "fmi2CompletedIntegratorStep", event && terminate ? &enter : NULL, &end);
    if (event && terminate) *event = enter != 0, *terminate = end != 0;
    return status;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    return set_continuous_states(c, "fmi2SetContinuousStates", x, n);
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    return get_continuous_states(c, "fmi2GetContinuousStates", x, n);
}
/* FMI 2.0's state table (section 3.2.3; Reference-FMUs' masks alike): the derivatives from event mode on, the
   nominals also when instantiated, neither in initialization mode; both in the error state, for diagnosis. */
#define ME_AFTER_INITIALIZATION (EVENT_MODE | CONTINUOUS_TIME | TERMINATED | FAILED)
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
    return get_derivatives(c, "fmi2GetDerivatives", ME_AFTER_INITIALIZATION, dx, n);
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
    return get_event_indicators(c, "fmi2GetEventIndicators", z, n);
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    return get_nominals(c, "fmi2GetNominalsOfContinuousStates", INSTANTIATED | ME_AFTER_INITIALIZATION, x, n);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[]) {
    return directional_derivative(c, "fmi2GetDirectionalDerivative", u, nu, z, nz, dv, dz);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *v) {
    if (!allowed(c, "fmi2GetRealStatus", STEPPING | STEP_DISCARDED | TERMINATED)) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime || !v) return refuse(c, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is known");
    *v = ((Instance *)c)->time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *v) {
    if (!allowed(c, "fmi2GetBooleanStatus", STEPPING | STEP_DISCARDED | TERMINATED)) return fmi2Error;
    if (kind != fmi2Terminated || !v) return refuse(c, "fmi2GetBooleanStatus", "only fmi2Terminated is known");
    *v = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { return get_fmu_state(c, "fmi2GetFMUstate", s); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { return set_fmu_state(c, "fmi2SetFMUstate", s); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { return free_fmu_state(c, "fmi2FreeFMUstate", s); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    return serialized_size(c, "fmi2SerializedFMUstateSize", s, size);
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte out[], size_t size) {
    return serialize_fmu_state(c, "fmi2SerializeFMUstate", s, (unsigned char *)out, size);
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte data[], size_t size, fmi2FMUstate *s) {
    return deserialize_fmu_state(c, "fmi2DeSerializeFMUstate", (const unsigned char *)data, size, s);
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        return c ? refuse(c, #name, "not supported by this FMU") : fmi2Error;                                \
    }
FMI2_OTHERS(UNSUPPORTED)
