/*
 * The FMI 3.0 FMUs' Linux binary: the counterpart of fmi2_loader.c. fmi3InstantiateCoSimulation
 * finds a CPython (find_python.h), loads the wrapper (the FMI 3.0 framework over the Python model,
 * python_model.c, next to this file as PythonWrapper.so) and every FMI call is forwarded to it.
 */
#include "find_python.h"
#include "fmi3Functions.h"
#include "fmi3_calls.h"

#define POINTER(ret, name, params, args) static name##TYPE *p_##name;
FMI3_IMPLEMENTED(POINTER)
FMI3_UNSUPPORTED(POINTER)
static fmi3InstantiateCoSimulationTYPE *p_fmi3InstantiateCoSimulation;
static fmi3FreeInstanceTYPE *p_fmi3FreeInstance;

#define FORWARD(ret, name, params, args) \
    ret name params { return p_##name ? p_##name args : fmi3Error; }
FMI3_IMPLEMENTED(FORWARD)
FMI3_UNSUPPORTED(FORWARD)

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging_on, fmi3Boolean event_mode_used,
                                         fmi3Boolean early_return_allowed, const fmi3ValueReference required[],
                                         size_t n_required, fmi3InstanceEnvironment environment,
                                         fmi3LogMessageCallback log_message,
                                         fmi3IntermediateUpdateCallback intermediate_update) {
    char message[10000], used[4400];
    void *wrapper = load_wrapper("fmi3InstantiateCoSimulation", message, sizeof message, used, sizeof used);
    if (!wrapper) {
        if (log_message) log_message(environment, fmi3Error, "logStatusError", message);
        return NULL;
    }
    if (logging_on && log_message) log_message(environment, fmi3OK, "logAll", used);
#define RESOLVE(ret, name, params, args) p_##name = (name##TYPE *)dlsym(wrapper, #name);
    FMI3_IMPLEMENTED(RESOLVE)
    FMI3_UNSUPPORTED(RESOLVE)
    RESOLVE(, fmi3FreeInstance, , )
    RESOLVE(, fmi3InstantiateCoSimulation, , )
    return p_fmi3InstantiateCoSimulation
               ? p_fmi3InstantiateCoSimulation(name, token, resources, visible, logging_on, event_mode_used,
                                               early_return_allowed, required, n_required, environment,
                                               log_message, intermediate_update)
               : NULL;
}

/* Model exchange and scheduled execution: not offered (the model description says so). */
fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                          fmi3Boolean visible, fmi3Boolean logging_on,
                                          fmi3InstanceEnvironment environment, fmi3LogMessageCallback log_message) {
    (void)name, (void)token, (void)resources, (void)visible, (void)logging_on;
    if (log_message) log_message(environment, fmi3Error, "logStatusError", "this FMU supports co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
                                               fmi3Boolean visible, fmi3Boolean logging_on,
                                               fmi3InstanceEnvironment environment,
                                               fmi3LogMessageCallback log_message, fmi3ClockUpdateCallback clock,
                                               fmi3LockPreemptionCallback lock, fmi3UnlockPreemptionCallback unlock) {
    (void)clock, (void)lock, (void)unlock;
    return fmi3InstantiateModelExchange(name, token, resources, visible, logging_on, environment, log_message);
}

void fmi3FreeInstance(fmi3Instance c) {
    if (p_fmi3FreeInstance) p_fmi3FreeInstance(c);
}
