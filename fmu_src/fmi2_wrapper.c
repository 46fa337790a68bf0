/*
 * FMI 2.0 co-simulation API over a pythonfmu slave class (Fmi2Slave subclass).
 *
 * Replaces pythonfmu 0.7's Linux binary, which
 *   - never passes a message to the host's logger (fmi2SetDebugLogging is a no-op and every
 *     message, including the reason of an error, is dropped), and turns every Python
 *     exception into fmi2Fatal;
 *   - leaves about 43 Py* symbols for the host to provide, so a C or C++ importer cannot
 *     load it (undefined symbol: _Py_NoneStruct).
 * This library is linked against libpython (with its folder as rpath), promotes libpython's
 * symbols to global scope before starting an interpreter in a non-Python host, reports a
 * Python exception as fmi2Error with the exception's text as the log message, and passes on
 * the slave's own log messages. Inside a Python host it uses that host's interpreter.
 *
 * The slave is found from resources/slavemodule.txt (module) and resources/slaveclass.txt
 * (class), both written by build_scripts/build_fmus.py.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define EXPORT __attribute__((visibility("default")))

typedef struct {
    PyObject *cls;     /* the slave class */
    PyObject *slave;   /* the slave instance */
    PyObject *queue;   /* slave.log_queue */
    PyObject *strings; /* bytes returned by the last fmi2GetString, kept alive until the next call */
    char *name;
    char *resources;
    fmi2CallbackFunctions cb;
    int logging_on;
    double last_successful_time;
} Instance;

static void log_text(const Instance *c, fmi2Status status, const char *category, const char *text) {
    if (c->cb.logger && (status != fmi2OK || c->logging_on))
        c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", text);
}

/* The pending Python exception as the log message of an fmi2Error. */
static fmi2Status python_error(const Instance *c, const char *function) {
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    PyErr_NormalizeException(&type, &value, &traceback);
    PyObject *text = value ? PyObject_Str(value) : NULL;
    const char *message = text ? PyUnicode_AsUTF8(text) : NULL;
    const char *kind = type ? ((PyTypeObject *)type)->tp_name : "error";
    char buffer[4096];
    if (type && PyErr_GivenExceptionMatches(type, PyExc_ValueError) && message && *message)
        snprintf(buffer, sizeof buffer, "%s: %s", function, message); /* our slaves' rule violations */
    else
        snprintf(buffer, sizeof buffer, "%s: %s: %s", function, kind, message ? message : "");
    PyErr_Clear();
    log_text(c, fmi2Error, "logStatusError", buffer);
    Py_XDECREF(text);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
    return fmi2Error;
}

/* Pass on and clear the messages the slave queued with Fmi2Slave.log(). */
static void flush_log(const Instance *c) {
    PyObject *queue = c->queue;
    if (!queue || PyList_GET_SIZE(queue) == 0) return;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(queue); i++) {
        PyObject *item = PyList_GET_ITEM(queue, i);
        PyObject *status = PyObject_GetAttrString(item, "status");
        PyObject *category = PyObject_GetAttrString(item, "category");
        PyObject *msg = PyObject_GetAttrString(item, "msg");
        long level = status ? PyLong_AsLong(status) : 0;
        const char *cat = category && PyUnicode_Check(category) ? PyUnicode_AsUTF8(category) : "logAll";
        const char *text = msg && PyUnicode_Check(msg) ? PyUnicode_AsUTF8(msg) : "";
        if (!PyErr_Occurred())
            log_text(c, (fmi2Status)(level >= 0 && level <= 4 ? level : 0), cat, text);
        PyErr_Clear();
        Py_XDECREF(status);
        Py_XDECREF(category);
        Py_XDECREF(msg);
    }
    PyList_SetSlice(queue, 0, PyList_GET_SIZE(queue), NULL);
}

/* Call slave.method(*args) (args stolen); on success keep the result in *result if given. */
static fmi2Status call(Instance *c, const char *function, const char *method, PyObject *args, PyObject **result) {
    if (!c || !c->slave) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    fmi2Status status = fmi2OK;
    PyObject *bound = args ? PyObject_GetAttrString(c->slave, method) : NULL;
    PyObject *out = args ? (bound ? PyObject_CallObject(bound, args) : NULL)
                         : PyObject_CallMethod(c->slave, method, NULL);
    Py_XDECREF(bound);
    Py_XDECREF(args);
    if (!out) {
        status = python_error(c, function);
    } else if (result) {
        *result = out;
    } else {
        Py_DECREF(out);
    }
    flush_log(c);
    PyGILState_Release(gil);
    return status;
}

static PyObject *vr_list(const fmi2ValueReference vr[], size_t nvr) {
    PyObject *list = PyList_New((Py_ssize_t)nvr);
    for (size_t i = 0; list && i < nvr; i++)
        PyList_SET_ITEM(list, (Py_ssize_t)i, PyLong_FromUnsignedLong(vr[i]));
    return list;
}

static char *read_line(const char *folder, const char *file) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", folder, file);
    FILE *f = fopen(path, "r");
    if (!f) return NULL;
    char line[512] = {0};
    if (!fgets(line, sizeof line, f)) line[0] = 0;
    fclose(f);
    line[strcspn(line, "\r\n")] = 0;
    return strdup(line);
}

/* file:///a%20b/resources -> /a b/resources */
static char *uri_to_path(const char *uri) {
    if (!uri) return NULL;
    const char *p = uri;
    if (strncmp(p, "file://", 7) == 0) p += 7;
    else if (strncmp(p, "file:", 5) == 0) p += 5;
    if (strncmp(p, "localhost/", 10) == 0) p += 9;
    char *out = malloc(strlen(p) + 1), *o = out;
    for (; *p; p++) {
        if (*p == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            *o++ = (char)strtol(hex, NULL, 16);
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    *o = 0;
    size_t n = strlen(out);
    if (n > 1 && out[n - 1] == '/') out[n - 1] = 0;
    return out;
}

/* In a non-Python host: make libpython's symbols global (extension modules need them) and
   start an interpreter whose GIL every call then takes with PyGILState_Ensure. */
static void ensure_python(void) {
    if (Py_IsInitialized()) return;
    Dl_info info;
    if (dladdr((void *)&Py_IsInitialized, &info) && info.dli_fname)
        dlopen(info.dli_fname, RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD);
    Py_InitializeEx(0);
    PyEval_SaveThread();
}

/* A new slave instance (replacing any previous one); 0 on a Python error. */
static int new_slave(Instance *c, int visible) {
    PyObject *kwargs = Py_BuildValue("{s:s,s:s,s:O}", "instance_name", c->name, "resources", c->resources,
                                     "visible", visible ? Py_True : Py_False);
    PyObject *args = PyTuple_New(0);
    PyObject *slave = kwargs && args ? PyObject_Call(c->cls, args, kwargs) : NULL;
    Py_XDECREF(args);
    Py_XDECREF(kwargs);
    if (!slave) return 0;
    PyObject *queue = PyObject_GetAttrString(slave, "log_queue");
    if (queue && !PyList_Check(queue)) Py_CLEAR(queue);
    PyErr_Clear();
    Py_XSETREF(c->slave, slave);
    Py_XSETREF(c->queue, queue);
    return 1;
}

static void free_instance(Instance *c) {
    free(c->name);
    free(c->resources);
    free(c);
}

EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                     const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                     fmi2Boolean loggingOn) {
    (void)guid;
    if (!functions || !name) return NULL;
    Instance *c = calloc(1, sizeof *c);
    c->cb = *functions;
    c->name = strdup(name);
    c->logging_on = loggingOn;
    c->resources = uri_to_path(location);
    if (type != fmi2CoSimulation || !c->resources) {
        log_text(c, fmi2Error, "logStatusError",
                 type != fmi2CoSimulation ? "fmi2Instantiate: only co-simulation is supported"
                                          : "fmi2Instantiate: no resource location given");
        free_instance(c);
        return NULL;
    }
    char *module_name = read_line(c->resources, "slavemodule.txt");
    char *class_name = read_line(c->resources, "slaveclass.txt");
    if (!module_name || !class_name) {
        char text[4200];
        snprintf(text, sizeof text, "fmi2Instantiate: cannot read slavemodule.txt and slaveclass.txt in %s",
                 c->resources);
        log_text(c, fmi2Error, "logStatusError", text);
        free(module_name);
        free(class_name);
        free_instance(c);
        return NULL;
    }
    ensure_python();
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *sys_path = PySys_GetObject("path"); /* borrowed */
    PyObject *folder = PyUnicode_FromString(c->resources);
    if (sys_path && folder && !PySequence_Contains(sys_path, folder)) PyList_Insert(sys_path, 0, folder);
    Py_XDECREF(folder);
    PyObject *module = PyImport_ImportModule(module_name);
    c->cls = module ? PyObject_GetAttrString(module, class_name) : NULL;
    Py_XDECREF(module);
    if (!c->cls || !new_slave(c, visible)) {
        python_error(c, "fmi2Instantiate");
        Py_XDECREF(c->cls);
        PyGILState_Release(gil);
        free(module_name);
        free(class_name);
        free_instance(c);
        return NULL;
    }
    flush_log(c);
    PyGILState_Release(gil);
    free(module_name);
    free(class_name);
    return c;
}

EXPORT void fmi2FreeInstance(fmi2Component component) {
    Instance *c = component;
    if (!c) return;
    PyGILState_STATE gil = PyGILState_Ensure();
    Py_XDECREF(c->slave);
    Py_XDECREF(c->queue);
    Py_XDECREF(c->cls);
    Py_XDECREF(c->strings);
    PyGILState_Release(gil);
    free_instance(c);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean loggingOn, size_t n,
                                      const fmi2String categories[]) {
    (void)n;
    (void)categories;
    if (!component) return fmi2Error;
    ((Instance *)component)->logging_on = loggingOn;
    return fmi2OK;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                      fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *c = component;
    if (!c) return fmi2Error;
    c->last_successful_time = startTime;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dNN)", startTime,
                                   stopTimeDefined ? PyFloat_FromDouble(stopTime) : Py_NewRef(Py_None),
                                   toleranceDefined ? PyFloat_FromDouble(tolerance) : Py_NewRef(Py_None));
    PyGILState_Release(gil);
    return call(c, "fmi2SetupExperiment", "setup_experiment", args, NULL);
}

EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return call(c, "fmi2EnterInitializationMode", "enter_initialization_mode", NULL, NULL);
}

EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return call(c, "fmi2ExitInitializationMode", "exit_initialization_mode", NULL, NULL);
}

EXPORT fmi2Status fmi2Terminate(fmi2Component c) { return call(c, "fmi2Terminate", "terminate", NULL, NULL); }

EXPORT fmi2Status fmi2Reset(fmi2Component component) {
    Instance *c = component;
    if (!c) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    fmi2Status status = new_slave(c, 0) ? fmi2OK : python_error(c, "fmi2Reset");
    PyGILState_Release(gil);
    return status;
}

/* fmi2Get<Type>: slave.get_<type>(vrs) -> sequence, converted by convert(item, i). */
#define GETTER(Name, method, ctype, convert)                                                                 \
    EXPORT fmi2Status Name(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,              \
                           ctype value[]) {                                                                  \
        Instance *c = component;                                                                             \
        if (!c) return fmi2Error;                                                                            \
        if (nvr == 0) return fmi2OK;                                                                         \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        PyObject *result = NULL;                                                                             \
        fmi2Status status = call(c, #Name, method, Py_BuildValue("(N)", vr_list(vr, nvr)), &result);         \
        if (status == fmi2OK) {                                                                              \
            PyObject *seq = PySequence_Fast(result, "get must return a sequence");                           \
            if (!seq || (size_t)PySequence_Fast_GET_SIZE(seq) != nvr) {                                      \
                if (seq) PyErr_SetString(PyExc_TypeError, "wrong number of values returned");                \
                status = python_error(c, #Name);                                                             \
            } else {                                                                                         \
                for (size_t i = 0; i < nvr; i++) {                                                           \
                    PyObject *item = PySequence_Fast_GET_ITEM(seq, (Py_ssize_t)i);                           \
                    convert;                                                                                 \
                }                                                                                            \
                if (PyErr_Occurred()) status = python_error(c, #Name);                                       \
            }                                                                                                \
            Py_XDECREF(seq);                                                                                 \
            Py_DECREF(result);                                                                               \
        }                                                                                                    \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

GETTER(fmi2GetReal, "get_real", fmi2Real, value[i] = PyFloat_AsDouble(item))
GETTER(fmi2GetInteger, "get_integer", fmi2Integer, value[i] = (fmi2Integer)PyLong_AsLong(item))
GETTER(fmi2GetBoolean, "get_boolean", fmi2Boolean, value[i] = PyObject_IsTrue(item))
GETTER(fmi2GetString, "get_string", fmi2String, {
    if (i == 0) Py_XSETREF(c->strings, PyList_New(0));
    PyObject *bytes = PyUnicode_AsUTF8String(item);
    value[i] = bytes ? PyBytes_AsString(bytes) : "";
    if (bytes) {
        PyList_Append(c->strings, bytes);
        Py_DECREF(bytes);
    }
})

/* fmi2Set<Type>: slave.set_<type>(vrs, values). */
#define SETTER(Name, method, ctype, make)                                                                    \
    EXPORT fmi2Status Name(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,              \
                           const ctype value[]) {                                                            \
        Instance *c = component;                                                                             \
        if (!c) return fmi2Error;                                                                            \
        if (nvr == 0) return fmi2OK;                                                                         \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        PyObject *values = PyList_New((Py_ssize_t)nvr);                                                      \
        for (size_t i = 0; values && i < nvr; i++) PyList_SET_ITEM(values, (Py_ssize_t)i, make);             \
        fmi2Status status = call(c, #Name, method, Py_BuildValue("(NN)", vr_list(vr, nvr), values), NULL);   \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

SETTER(fmi2SetReal, "set_real", fmi2Real, PyFloat_FromDouble(value[i]))
SETTER(fmi2SetInteger, "set_integer", fmi2Integer, PyLong_FromLong(value[i]))
SETTER(fmi2SetBoolean, "set_boolean", fmi2Boolean, PyBool_FromLong(value[i]))
SETTER(fmi2SetString, "set_string", fmi2String, PyUnicode_FromString(value[i] ? value[i] : ""))

EXPORT fmi2Status fmi2DoStep(fmi2Component component, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    (void)noSetPrior;
    Instance *c = component;
    if (!c) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = NULL;
    fmi2Status status = call(c, "fmi2DoStep", "do_step", Py_BuildValue("(dd)", t, h), &result);
    if (status == fmi2OK) {
        int ok = PyObject_IsTrue(result);
        Py_DECREF(result);
        status = ok ? fmi2OK : fmi2Discard;
        if (ok) c->last_successful_time = t + h;
    }
    PyGILState_Release(gil);
    return status;
}

static fmi2Status unsupported(fmi2Component component, const char *function) {
    char text[256];
    snprintf(text, sizeof text, "%s is not supported by this FMU", function);
    if (component) log_text(component, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

EXPORT fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStatus");
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind s, fmi2Real *value) {
    if (component && s == fmi2LastSuccessfulTime && value) {
        *value = ((Instance *)component)->last_successful_time;
        return fmi2OK;
    }
    return unsupported(component, "fmi2GetRealStatus for this status kind");
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component component, const fmi2StatusKind s, fmi2Boolean *value) {
    if (component && s == fmi2Terminated && value) {
        *value = 0;
        return fmi2OK;
    }
    return unsupported(component, "fmi2GetBooleanStatus for this status kind");
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}

/* FMU states are the Python objects of the slave's _get_fmu_state(); serialised with its
   _fmu_state_to_bytes() and read back with _fmu_state_from_bytes(). */
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component component, fmi2FMUstate *state) {
    Instance *c = component;
    if (!c || !state) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = NULL;
    fmi2Status status = call(c, "fmi2GetFMUstate", "_get_fmu_state", PyTuple_New(0), &result);
    if (status == fmi2OK) {
        Py_XDECREF((PyObject *)*state); /* an existing state is overwritten */
        *state = result;
    }
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component component, fmi2FMUstate state) {
    if (!component || !state) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    fmi2Status status = call(component, "fmi2SetFMUstate", "_set_fmu_state",
                             Py_BuildValue("(O)", (PyObject *)state), NULL);
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component component, fmi2FMUstate *state) {
    if (!component || !state) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    Py_XDECREF((PyObject *)*state);
    *state = NULL;
    PyGILState_Release(gil);
    return fmi2OK;
}

static fmi2Status state_bytes(Instance *c, const char *function, fmi2FMUstate state, PyObject **bytes) {
    if (!c || !state) return fmi2Error;
    fmi2Status status = call(c, function, "_fmu_state_to_bytes", Py_BuildValue("(O)", (PyObject *)state), bytes);
    if (status == fmi2OK && !PyBytes_Check(*bytes)) {
        Py_CLEAR(*bytes);
        PyErr_SetString(PyExc_TypeError, "_fmu_state_to_bytes must return bytes");
        status = python_error(c, function);
    }
    return status;
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component component, fmi2FMUstate state, size_t *size) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = NULL;
    fmi2Status status = state_bytes(component, "fmi2SerializedFMUstateSize", state, &bytes);
    if (status == fmi2OK) {
        *size = (size_t)PyBytes_GET_SIZE(bytes);
        Py_DECREF(bytes);
    }
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component component, fmi2FMUstate state, fmi2Byte out[], size_t size) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = NULL;
    fmi2Status status = state_bytes(component, "fmi2SerializeFMUstate", state, &bytes);
    if (status == fmi2OK) {
        if ((size_t)PyBytes_GET_SIZE(bytes) > size) {
            log_text(component, fmi2Error, "logStatusError", "fmi2SerializeFMUstate: the buffer is too small");
            status = fmi2Error;
        } else {
            memcpy(out, PyBytes_AS_STRING(bytes), (size_t)PyBytes_GET_SIZE(bytes));
        }
        Py_DECREF(bytes);
    }
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component component, const fmi2Byte data[], size_t size,
                                          fmi2FMUstate *state) {
    Instance *c = component;
    if (!c || !state || !data) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = NULL;
    fmi2Status status = call(c, "fmi2DeSerializeFMUstate", "_fmu_state_from_bytes",
                             Py_BuildValue("(y#)", data, (Py_ssize_t)size), &result);
    if (status == fmi2OK) {
        Py_XDECREF((PyObject *)*state);
        *state = result;
    }
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                               const fmi2ValueReference z[], size_t nz, const fmi2Real dv[],
                                               fmi2Real dz[]) {
    (void)u, (void)nu, (void)z, (void)nz, (void)dv, (void)dz;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                              const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                               const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}
