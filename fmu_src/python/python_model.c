/*
 * The Python model: the model interface (model.h) answered by a component's Python runtime, one pythonfmu (FMI 2.0)
 * or pythonfmu3 (FMI 3.0) slave object per instance (fmu_src/python/slave2.py, slave3.py, runtime.py). The FMI
 * framework around it (framework/fmi2Functions.c or fmi3Functions.c, compiled with FMI_VERSION 2 or 3) is the one
 * of the native FMUs: the state machine, the checks, the log and the FMU-state bookkeeping are there, not here.
 *
 * Python's limited API (3.10): one compiled model runs with every CPython from 3.10 on. The GIL: every function
 * here that touches Python takes it once (PyGILState_Ensure) and releases it before returning; the helpers expect
 * it held. Hot-path objects are cached per model: the slave's bound methods and, per value-reference array, the
 * argument tuple holding its value references and the slave's reader and writer of those Reals
 * (slave.real_reader(refs) and slave.real_writer(refs), asked for once: a Real get is then reader(), a set
 * writer(values)).
 */
#define Py_LIMITED_API 0x030A0000
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"

#if FMI_VERSION == 3
#define VR_OFFSET 1 /* the slave's value reference 0 is time: the framework's variable k is the slave's k + 1 */
#else
#define VR_OFFSET 0
#endif

/* The slave's methods this model calls. */
enum { SETUP, ENTER, EXIT, TERMINATE, DO_STEP, GET_STATE, SET_STATE, TO_BYTES, FROM_BYTES, GET_STR, SET_STR, READER,
       WRITER, GET_ENUM, SET_ENUM, N_METHODS };
static const char *const METHODS[N_METHODS] = {
    [SETUP] = "setup_experiment", [ENTER] = "enter_initialization_mode", [EXIT] = "exit_initialization_mode",
    [TERMINATE] = "terminate", [DO_STEP] = "do_step", [GET_STATE] = "_get_fmu_state",
    [SET_STATE] = "_set_fmu_state", [TO_BYTES] = "_fmu_state_to_bytes", [FROM_BYTES] = "_fmu_state_from_bytes",
    [GET_STR] = "get_string", [SET_STR] = "set_string", [READER] = "real_reader", [WRITER] = "real_writer",
    [GET_ENUM] = "get_enumerations", [SET_ENUM] = "set_enumerations"};

#define VR_CACHE 8
typedef struct {
    size_t n;
    unsigned int *vr;
    PyObject *args;   /* (tuple of the slave's value references,) */
    PyObject *reader; /* slave.real_reader(refs), once asked for */
    PyObject *writer; /* slave.real_writer(refs), once asked for */
    PyObject *fixed;  /* writer.fixed once asked for: the line refusing the fixed parameter among refs, or None */
} VrArgs;

/* One instance's model: the slave and what is cached of it. Holds Python objects: FMU states are the slave's. */
typedef struct {
    PyObject *cls, *slave, *queue, *strings;
    PyObject *bound[N_METHODS];
    VrArgs vrs[VR_CACHE];
    int next_vr;
    Instantiation at; /* the instance's: its strings live as long as the instance */
} PythonModel;

static pthread_once_t python_once = PTHREAD_ONCE_INIT;

/* In a non-Python host, start an interpreter (once per process) and release its GIL; every call then takes the
   GIL with PyGILState_Ensure. In a Python host, the host's interpreter is used. */
static void start_python(void) {
    if (Py_IsInitialized()) return;
    Py_InitializeEx(0);
    PyEval_SaveThread();
}

/* ---- messages: the slave's queue and Python exceptions, to the framework's reporter ---- */

/* Pass on, then clear, the messages the slave queued with its log() method, each with its status. */
static void flush_log(const PythonModel *p, const Reporter *r) {
    if (!p->queue || PyList_Size(p->queue) <= 0) return;
    for (Py_ssize_t i = 0; i < PyList_Size(p->queue); i++) {
        PyObject *item = PyList_GetItem(p->queue, i); /* borrowed */
        PyObject *status = item ? PyObject_GetAttrString(item, "status") : NULL;
        PyObject *msg = item ? PyObject_GetAttrString(item, "msg") : NULL;
        long level = status ? PyLong_AsLong(status) : 0;
        const char *text = msg && PyUnicode_Check(msg) ? PyUnicode_AsUTF8AndSize(msg, NULL) : NULL;
        if (!PyErr_Occurred())
            report(r, level >= 0 && level <= MODEL_ERROR ? (ModelStatus)level : MODEL_ERROR, "%s", text ? text : "");
        PyErr_Clear();
        Py_XDECREF(status);
        Py_XDECREF(msg);
    }
    PyList_SetSlice(p->queue, 0, PyList_Size(p->queue), NULL);
    PyErr_Clear();
}

/* Report the pending Python exception as an error (the framework names the FMI function), and clear it. */
static void python_error(const Reporter *r) {
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    PyErr_NormalizeException(&type, &value, &traceback);
    PyObject *text = value ? PyObject_Str(value) : NULL;
    PyObject *kind = type ? PyObject_GetAttrString(type, "__name__") : NULL;
    const char *message = text ? PyUnicode_AsUTF8AndSize(text, NULL) : NULL;
    const char *kind_text = kind ? PyUnicode_AsUTF8AndSize(kind, NULL) : NULL;
    if (type && PyErr_GivenExceptionMatches(type, PyExc_ValueError) && message && *message)
        report(r, MODEL_ERROR, "%s", message); /* our slaves' rule violations */
    else
        report(r, MODEL_ERROR, "%s: %s", kind_text ? kind_text : "error", message ? message : "(no message)");
    PyErr_Clear();
    Py_XDECREF(text);
    Py_XDECREF(kind);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
}

/* The status of a Python call (ok: it succeeded): the slave's queued messages, then on failure the exception. */
static ModelStatus finish(const PythonModel *p, int ok, const Reporter *r) {
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    flush_log(p, r);
    PyErr_Restore(type, value, traceback);
    if (ok) return MODEL_OK;
    python_error(r);
    return MODEL_ERROR;
}

/* ---- calls into the slave (GIL held) ---- */

/* slave.<method>(*args) (args may be NULL): a new reference, or NULL with a Python exception set. */
static PyObject *call_method(PythonModel *p, int method, PyObject *args) {
    if (!p->slave) {
        PyErr_SetString(PyExc_RuntimeError, "this instance has no Python slave (it could not be created)");
        return NULL;
    }
    if (!p->bound[method]) {
        p->bound[method] = PyObject_GetAttrString(p->slave, METHODS[method]);
        if (!p->bound[method]) return NULL;
    }
    return PyObject_CallObject(p->bound[method], args);
}

/* The cache entry of this value-reference array (made if new), NULL on a Python error. */
static VrArgs *vr_entry(PythonModel *p, const unsigned int vr[], size_t n) {
    for (int i = 0; i < VR_CACHE; i++) {
        VrArgs *e = &p->vrs[i];
        if (e->args && e->n == n && memcmp(e->vr, vr, n * sizeof *vr) == 0) return e;
    }
    PyObject *refs = PyTuple_New((Py_ssize_t)n);
    for (size_t i = 0; refs && i < n; i++) {
        PyObject *ref = PyLong_FromUnsignedLong(vr[i] + VR_OFFSET);
        if (!ref || PyTuple_SetItem(refs, (Py_ssize_t)i, ref) < 0) Py_CLEAR(refs);
    }
    PyObject *args = refs ? PyTuple_Pack(1, refs) : NULL;
    Py_XDECREF(refs);
    unsigned int *copy = args ? malloc(n * sizeof *vr + 1) : NULL;
    if (!copy) {
        Py_XDECREF(args);
        if (!PyErr_Occurred()) PyErr_NoMemory();
        return NULL;
    }
    memcpy(copy, vr, n * sizeof *vr);
    VrArgs *e = &p->vrs[p->next_vr];
    p->next_vr = (p->next_vr + 1) % VR_CACHE;
    Py_XDECREF(e->args);
    Py_XDECREF(e->reader);
    Py_XDECREF(e->writer);
    Py_XDECREF(e->fixed);
    free(e->vr);
    *e = (VrArgs){n, copy, args, NULL, NULL, NULL};
    return e;
}

/* *prepared, made by slave.<method>(refs) if not yet: borrowed, NULL on a Python error. */
static PyObject *prepared(PythonModel *p, PyObject **prepared, int method, PyObject *args) {
    if (!*prepared) *prepared = call_method(p, method, args);
    return *prepared;
}

/* A list or tuple of n items from `values` (a new reference, stolen), else NULL with a Python exception. */
static PyObject *sized(PyObject *values, size_t n, const char *method) {
    if (values && !((PyList_Check(values) || PyTuple_Check(values)) && (size_t)PyObject_Size(values) == n)) {
        Py_DECREF(values);
        PyErr_Format(PyExc_TypeError, "%s must return a list of %zu values", method, n);
        return NULL;
    }
    return values;
}

/* Item i of a list or tuple (borrowed). */
static PyObject *item(PyObject *values, size_t i) {
    return PyList_Check(values) ? PyList_GetItem(values, (Py_ssize_t)i) : PyTuple_GetItem(values, (Py_ssize_t)i);
}

/* Forget what belongs to the slave object: its bound methods, readers and writers. */
static void forget_methods(PythonModel *p) {
    for (int i = 0; i < N_METHODS; i++) Py_CLEAR(p->bound[i]);
    for (int i = 0; i < VR_CACHE; i++) {
        Py_CLEAR(p->vrs[i].reader);
        Py_CLEAR(p->vrs[i].writer);
        Py_CLEAR(p->vrs[i].fixed);
    }
}

static char *read_line(const char *folder, const char *file) {
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", folder, file);
    FILE *f = fopen(path, "r");
    if (!f) return NULL;
    char line[512] = {0};
    if (!fgets(line, sizeof line, f)) line[0] = 0;
    fclose(f);
    line[strcspn(line, "\r\n")] = 0;
    return line[0] ? strdup(line) : NULL;
}

/* The slave class named in the resources, imported (with the resources first on sys.path); NULL with a
   Python exception set. */
static PyObject *slave_class(const char *resources) {
    char *module_name = read_line(resources, "slavemodule.txt");
    char *class_name = read_line(resources, "slaveclass.txt");
    PyObject *cls = NULL;
    if (!module_name || !class_name) {
        PyErr_Format(PyExc_ValueError, "cannot read slavemodule.txt and slaveclass.txt in %s", resources);
    } else {
        PyObject *sys_path = PySys_GetObject("path"); /* borrowed */
        PyObject *folder = PyUnicode_FromString(resources);
        if (sys_path && folder && PySequence_Contains(sys_path, folder) == 0) PyList_Insert(sys_path, 0, folder);
        Py_XDECREF(folder);
        PyObject *module = PyErr_Occurred() ? NULL : PyImport_ImportModule(module_name);
        cls = module ? PyObject_GetAttrString(module, class_name) : NULL;
        Py_XDECREF(module);
    }
    free(module_name);
    free(class_name);
    return cls;
}

/* The slave object of the class, with its log queue; 0 with a Python exception set. */
static int new_slave(PythonModel *p) {
    PyObject *kwargs = Py_BuildValue("{s:s,s:s,s:O}", "instance_name", p->at.instance_name, "resources",
                                     p->at.resources, "visible", p->at.visible ? Py_True : Py_False);
    PyObject *args = kwargs ? PyTuple_New(0) : NULL;
    PyObject *slave = args ? PyObject_Call(p->cls, args, kwargs) : NULL;
    Py_XDECREF(args);
    Py_XDECREF(kwargs);
    if (!slave) return 0;
    PyObject *queue = PyObject_GetAttrString(slave, "log_queue");
    if (!queue || !PyList_Check(queue)) Py_CLEAR(queue); /* a slave without a queue logs nothing */
    PyErr_Clear();
    p->slave = slave;
    p->queue = queue;
    return 1;
}

/* ---- the model interface ---- */

static size_t python_size(const ModelType *type) {
    (void)type;
    return sizeof(PythonModel);
}

/* The slave class from the resources and a new slave object (also at a reset, with the class imported again:
   Python keeps the module, so that costs a lookup). */
static ModelStatus python_instantiate(const ModelType *type, void *m, const Instantiation *at, const Reporter *r) {
    PythonModel *p = m;
    p->at = *at;
    if (!at->resources) return report(r, MODEL_ERROR, "no resource location given");
    pthread_once(&python_once, start_python);
    PyGILState_STATE gil = PyGILState_Ensure();
    p->cls = slave_class(at->resources);
    ModelStatus status = finish(p, p->cls && new_slave(p), r);
    PyGILState_Release(gil);
    return status;
}

static void python_free(const ModelType *type, void *m) {
    PythonModel *p = m;
    if (!Py_IsInitialized()) return; /* nothing was made */
    PyGILState_STATE gil = PyGILState_Ensure();
    forget_methods(p);
    for (int i = 0; i < VR_CACHE; i++) {
        Py_CLEAR(p->vrs[i].args);
        free(p->vrs[i].vr);
        p->vrs[i].vr = NULL;
    }
    Py_CLEAR(p->slave);
    Py_CLEAR(p->queue);
    Py_CLEAR(p->cls);
    Py_CLEAR(p->strings);
    PyGILState_Release(gil);
}

/* slave.<method>(args) (args: NULL, or a new reference taken here), the GIL taken once; its status. */
static ModelStatus call(PythonModel *p, int method, PyObject *args, const Reporter *r) {
    PyObject *result = call_method(p, method, args);
    ModelStatus status = finish(p, result != NULL, r);
    Py_XDECREF(args);
    Py_XDECREF(result);
    return status;
}

static ModelStatus python_setup_experiment(const ModelType *type, void *m, const Experiment *e, const Reporter *r) {
    PyGILState_STATE gil = PyGILState_Ensure();
#if FMI_VERSION == 3
    PyObject *args = Py_BuildValue("(d)", e->start); /* pythonfmu3's setup_experiment(start_time) */
#else
    PyObject *args = Py_BuildValue("(dNN)", e->start, e->stop_defined ? PyFloat_FromDouble(e->stop) : Py_NewRef(Py_None),
                                   e->tolerance_defined ? PyFloat_FromDouble(e->tolerance) : Py_NewRef(Py_None));
#endif
    ModelStatus status = args ? call(m, SETUP, args, r) : finish(m, 0, r);
    PyGILState_Release(gil);
    return status;
}

#define SIMPLE_CALL(name, method)                                                                            \
    static ModelStatus name(const ModelType *type, void *m, const Reporter *r) {                             \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        ModelStatus status = call(m, method, NULL, r);                                                       \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }
SIMPLE_CALL(python_enter_initialization, ENTER)
SIMPLE_CALL(python_exit_initialization, EXIT)
SIMPLE_CALL(python_terminate, TERMINATE)

/* reader() of these value references: n Reals into v. */
static ModelStatus python_get_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, double v[],
                                    const Reporter *r) {
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    VrArgs *e = vr_entry(p, vr, n);
    PyObject *reader = e ? prepared(p, &e->reader, READER, e->args) : NULL;
    PyObject *values = sized(reader ? PyObject_CallNoArgs(reader) : NULL, n, METHODS[READER]);
    for (size_t i = 0; values && i < n; i++) {
        v[i] = PyFloat_AsDouble(item(values, i));
        if (PyErr_Occurred()) Py_CLEAR(values);
    }
    ModelStatus status = finish(p, values != NULL, r);
    Py_XDECREF(values);
    PyGILState_Release(gil);
    return status;
}

/* writer(values) of these value references. */
static ModelStatus python_set_reals(const ModelType *type, void *m, const unsigned vr[], size_t n, const double v[],
                                    int fixed_allowed, const Reporter *r) {
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *values = PyList_New((Py_ssize_t)n);
    for (size_t i = 0; values && i < n; i++) {
        PyObject *x = PyFloat_FromDouble(v[i]);
        if (!x || PyList_SetItem(values, (Py_ssize_t)i, x) < 0) Py_CLEAR(values);
    }
    VrArgs *e = values ? vr_entry(p, vr, n) : NULL;
    PyObject *writer = e ? prepared(p, &e->writer, WRITER, e->args) : NULL;
    if (writer && !e->fixed) { /* runtime.real_writer names a parameter among refs: component.c's store_reals */
        e->fixed = PyObject_GetAttrString(writer, "fixed");
        if (!e->fixed) PyErr_Clear(), e->fixed = Py_NewRef(Py_None);
    }
    if (writer && !fixed_allowed && e->fixed != Py_None) {
        PyObject *bytes = PyUnicode_AsUTF8String(e->fixed);
        ModelStatus status = bytes ? report(r, MODEL_ERROR, "%s", PyBytes_AsString(bytes)) : finish(p, 0, r);
        Py_XDECREF(bytes);
        Py_DECREF(values);
        PyGILState_Release(gil);
        return status;
    }
    PyObject *result = writer ? PyObject_CallFunctionObjArgs(writer, values, NULL) : NULL;
    ModelStatus status = finish(p, result != NULL, r);
    Py_XDECREF(values);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    return status;
}

/* The bytes of a str, kept alive in p->strings until the next get (FMI's rule); NULL with a Python exception. */
static const char *keep_string(PythonModel *p, PyObject *value, size_t i) {
    if (i == 0) {
        Py_XDECREF(p->strings);
        p->strings = PyList_New(0);
    }
    PyObject *bytes = p->strings && PyUnicode_Check(value) ? PyUnicode_AsUTF8String(value) : NULL;
    if (!bytes || PyList_Append(p->strings, bytes) < 0) {
        Py_XDECREF(bytes);
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "a String variable must hold a str");
        return NULL;
    }
    Py_DECREF(bytes);
    return PyBytes_AsString(bytes); /* alive in p->strings */
}

static ModelStatus python_get_strings(const ModelType *type, void *m, const unsigned vr[], size_t n, const char *v[],
                                      const Reporter *r) {
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    VrArgs *e = vr_entry(p, vr, n);
    PyObject *values = sized(e ? call_method(p, GET_STR, e->args) : NULL, n, METHODS[GET_STR]);
    for (size_t i = 0; values && i < n; i++)
        if (!(v[i] = keep_string(p, item(values, i), i))) Py_CLEAR(values);
    ModelStatus status = finish(p, values != NULL, r);
    Py_XDECREF(values);
    PyGILState_Release(gil);
    return status;
}

static ModelStatus python_set_strings(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                      const char *const v[], int fixed_allowed, const Reporter *r) {
    if (!fixed_allowed) /* a String is a parameter (runtime.py: inputs are Real), and every parameter is fixed */
        return report(r, MODEL_ERROR, "a String is a fixed parameter: it can be set only before initialisation ends");
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *values = PyList_New((Py_ssize_t)n);
    for (size_t i = 0; values && i < n; i++) {
        PyObject *x = PyUnicode_FromString(v[i] ? v[i] : "");
        if (!x || PyList_SetItem(values, (Py_ssize_t)i, x) < 0) Py_CLEAR(values);
    }
    VrArgs *e = values ? vr_entry(p, vr, n) : NULL;
    PyObject *args = e ? PyTuple_Pack(2, PyTuple_GetItem(e->args, 0), values) : NULL;
    ModelStatus status = args ? call(p, SET_STR, args, r) : finish(p, 0, r);
    Py_XDECREF(values);
    PyGILState_Release(gil);
    return status;
}

/* slave.do_step(t, h): true is a step taken, false a step discarded (the slave logged why). */
static ModelStatus python_do_step(const ModelType *type, void *m, double time, double step, const Reporter *r) {
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dd)", time, step);
    PyObject *result = args ? call_method(p, DO_STEP, args) : NULL;
    int done = result ? PyObject_IsTrue(result) : -1;
    Py_XDECREF(args);
    Py_XDECREF(result);
    ModelStatus status = finish(p, done >= 0, r);
    PyGILState_Release(gil);
    return status == MODEL_OK && !done ? MODEL_DISCARD : status;
}

/* ---- FMU states: the slave's state objects ---- */

/* *saved = `object` (a new reference; NULL after a Python error), the object it held released. */
static ModelStatus store(PythonModel *p, void **saved, PyObject *object, const Reporter *r) {
    if (object) {
        Py_XDECREF((PyObject *)*saved);
        *saved = object;
    }
    return finish(p, object != NULL, r);
}

static ModelStatus python_save(const ModelType *type, void *m, void **saved, const Reporter *r) {
    PyGILState_STATE gil = PyGILState_Ensure();
    ModelStatus status = store(m, saved, call_method(m, GET_STATE, NULL), r);
    PyGILState_Release(gil);
    return status;
}

static ModelStatus python_restore(const ModelType *type, void *m, const void *saved, const Reporter *r) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = PyTuple_Pack(1, (PyObject *)saved);
    ModelStatus status = args ? call(m, SET_STATE, args, r) : finish(m, 0, r);
    PyGILState_Release(gil);
    return status;
}

static void python_discard(const ModelType *type, void *saved) {
    PyGILState_STATE gil = PyGILState_Ensure();
    Py_XDECREF((PyObject *)saved);
    PyGILState_Release(gil);
}

static ModelStatus python_serialize(const ModelType *type, void *m, const void *saved, unsigned char **bytes,
                                    size_t *size, const Reporter *r) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = PyTuple_Pack(1, (PyObject *)saved);
    PyObject *data = args ? call_method(m, TO_BYTES, args) : NULL;
    Py_XDECREF(args);
    if (data && !PyBytes_Check(data)) {
        Py_CLEAR(data);
        PyErr_SetString(PyExc_TypeError, "_fmu_state_to_bytes must return bytes");
    }
    *size = data ? (size_t)PyBytes_Size(data) : 0;
    *bytes = data ? malloc(*size + 1) : NULL;
    if (data && !*bytes) PyErr_NoMemory();
    else if (data) memcpy(*bytes, PyBytes_AsString(data), *size);
    ModelStatus status = finish(m, *bytes != NULL, r);
    Py_XDECREF(data);
    PyGILState_Release(gil);
    return status;
}

static ModelStatus python_deserialize(const ModelType *type, void *m, const unsigned char bytes[], size_t size,
                                      void **saved, const Reporter *r) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(y#)", (const char *)bytes, (Py_ssize_t)size);
    PyObject *object = args ? call_method(m, FROM_BYTES, args) : NULL;
    Py_XDECREF(args);
    ModelStatus status = store(m, saved, object, r);
    PyGILState_Release(gil);
    return status;
}

static const StateFunctions PYTHON_STATES = {python_save, python_restore, python_discard, python_serialize,
                                             python_deserialize};

/* Enumerations by their items' values (runtime.SlaveCalls.get_enumerations, set_enumerations). */
static ModelStatus python_get_integers(const ModelType *type, void *m, const unsigned vr[], size_t n, long long v[],
                                       const Reporter *r) {
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    VrArgs *e = vr_entry(p, vr, n);
    PyObject *values = sized(e ? call_method(p, GET_ENUM, e->args) : NULL, n, METHODS[GET_ENUM]);
    for (size_t i = 0; values && i < n; i++) {
        v[i] = PyLong_AsLongLong(item(values, i));
        if (PyErr_Occurred()) Py_CLEAR(values);
    }
    ModelStatus status = finish(p, values != NULL, r);
    Py_XDECREF(values);
    PyGILState_Release(gil);
    return status;
}

static ModelStatus python_set_integers(const ModelType *type, void *m, const unsigned vr[], size_t n,
                                       const long long v[], int fixed_allowed, const Reporter *r) {
    if (!fixed_allowed)
        return report(r, MODEL_ERROR, "an Enumeration is a fixed parameter: it can be set only before initialisation "
                                      "ends");
    PythonModel *p = m;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *values = PyList_New((Py_ssize_t)n);
    for (size_t i = 0; values && i < n; i++) {
        PyObject *x = PyLong_FromLongLong(v[i]);
        if (!x || PyList_SetItem(values, (Py_ssize_t)i, x) < 0) Py_CLEAR(values);
    }
    VrArgs *e = values ? vr_entry(p, vr, n) : NULL;
    PyObject *args = e ? PyTuple_Pack(2, PyTuple_GetItem(e->args, 0), values) : NULL;
    ModelStatus status = args ? call(p, SET_ENUM, args, r) : finish(p, 0, r);
    Py_XDECREF(values);
    PyGILState_Release(gil);
    return status;
}

static const ModelType PYTHON_MODEL = {.identifier = "the Python slave", /* the FMU's is its slave class's */
                                       .size = python_size,
                                       .instantiate = python_instantiate,
                                       .free = python_free,
                                       .setup_experiment = python_setup_experiment,
                                       .enter_initialization = python_enter_initialization,
                                       .exit_initialization = python_exit_initialization,
                                       .terminate = python_terminate,
                                       .get_reals = python_get_reals,
                                       .set_reals = python_set_reals,
                                       .get_strings = python_get_strings,
                                       .set_strings = python_set_strings,
                                       .get_integers = python_get_integers,
                                       .set_integers = python_set_integers,
                                       .do_step = python_do_step,
                                       .states = &PYTHON_STATES};

const ModelType *const FMU_MODEL = &PYTHON_MODEL;
