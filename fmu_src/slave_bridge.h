/*
 * The Python side of the FMI wrappers (fmi2_wrapper.c, fmi3_wrapper.c): one pythonfmu (or
 * pythonfmu3) slave object per FMU instance, called through Python's limited API (3.10), so that
 * one compiled wrapper runs with every CPython from 3.10 on.
 *
 * The GIL: every exported FMI function that touches Python takes it once (PyGILState_Ensure) and
 * releases it before returning; the functions here expect it held and never take it again.
 * Hot-path objects are cached per instance: the slave's bound methods and, per value-reference
 * array, the argument tuple holding its value references.
 */
#define Py_LIMITED_API 0x030A0000
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The slave's methods the wrappers call; each wrapper names them for its FMI version. */
enum { SETUP, ENTER, EXIT, TERMINATE, DO_STEP, GET_STATE, SET_STATE, TO_BYTES, FROM_BYTES, GET_F64, SET_F64,
       GET_I32, SET_I32, GET_I64, SET_I64, GET_U64, SET_U64, GET_BOOL, SET_BOOL, GET_STR, SET_STR, N_METHODS };

enum { LOG_OK, LOG_WARNING, LOG_DISCARD, LOG_ERROR, LOG_FATAL }; /* the same numbers in FMI 2.0 and 3.0 */

typedef void (*Emit)(void *owner, int status, const char *category, const char *text);

#define VR_CACHE 8
typedef struct {
    size_t n;
    unsigned int *vr;
    PyObject *args; /* (tuple of the value references,) */
} VrArgs;

typedef struct {
    PyObject *cls, *slave, *queue, *strings;
    PyObject *bound[N_METHODS];
    const char *const *names; /* method names by the enum above, NULL where the slave has none */
    VrArgs vrs[VR_CACHE];
    int next_vr;
    Emit emit;
    void *owner;
    char *name, *resources;
} Slave;

static pthread_once_t python_once = PTHREAD_ONCE_INIT;

/* In a non-Python host, start an interpreter (once per process) and release its GIL; every call
   then takes the GIL with PyGILState_Ensure. In a Python host, the host's interpreter is used. */
static void start_python(void) {
    if (Py_IsInitialized()) return;
    Py_InitializeEx(0);
    PyEval_SaveThread();
}

static void emit_text(const Slave *s, int status, const char *text) {
    static const char *const categories[] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError",
                                             "logStatusFatal"};
    s->emit(s->owner, status, categories[status >= 0 && status <= 4 ? status : 0], text);
}

/* Log the pending Python exception as the reason of `function`'s error, and clear it. */
static void python_error(const Slave *s, const char *function) {
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    PyErr_NormalizeException(&type, &value, &traceback);
    PyObject *text = value ? PyObject_Str(value) : NULL;
    PyObject *kind = type ? PyObject_GetAttrString(type, "__name__") : NULL;
    const char *message = text ? PyUnicode_AsUTF8AndSize(text, NULL) : NULL;
    const char *kind_text = kind ? PyUnicode_AsUTF8AndSize(kind, NULL) : NULL;
    char buffer[4096];
    if (type && PyErr_GivenExceptionMatches(type, PyExc_ValueError) && message && *message)
        snprintf(buffer, sizeof buffer, "%s: %s", function, message); /* our slaves' rule violations */
    else
        snprintf(buffer, sizeof buffer, "%s: %s: %s", function, kind_text ? kind_text : "error",
                 message ? message : "(no message)");
    PyErr_Clear();
    emit_text(s, LOG_ERROR, buffer);
    Py_XDECREF(text);
    Py_XDECREF(kind);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
}

/* Pass on, then clear, the messages the slave queued with its log() method. */
static void flush_log(const Slave *s) {
    if (!s->queue || PyList_Size(s->queue) <= 0) return;
    for (Py_ssize_t i = 0; i < PyList_Size(s->queue); i++) {
        PyObject *item = PyList_GetItem(s->queue, i); /* borrowed */
        PyObject *status = item ? PyObject_GetAttrString(item, "status") : NULL;
        PyObject *category = item ? PyObject_GetAttrString(item, "category") : NULL;
        PyObject *msg = item ? PyObject_GetAttrString(item, "msg") : NULL;
        long level = status ? PyLong_AsLong(status) : 0;
        const char *cat = category && PyUnicode_Check(category) ? PyUnicode_AsUTF8AndSize(category, NULL) : NULL;
        const char *text = msg && PyUnicode_Check(msg) ? PyUnicode_AsUTF8AndSize(msg, NULL) : NULL;
        if (!PyErr_Occurred())
            s->emit(s->owner, level >= 0 && level <= 4 ? (int)level : 0, cat ? cat : "logAll", text ? text : "");
        PyErr_Clear();
        Py_XDECREF(status);
        Py_XDECREF(category);
        Py_XDECREF(msg);
    }
    PyList_SetSlice(s->queue, 0, PyList_Size(s->queue), NULL);
    PyErr_Clear();
}

/* The slave's queued messages, then the pending exception as the reason of `function`'s error. */
static void log_failure(const Slave *s, const char *function) {
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    flush_log(s);
    PyErr_Restore(type, value, traceback);
    python_error(s, function);
}

/* slave.<method>(*args) (args may be NULL): a new reference, or NULL with a Python exception set. */
static PyObject *call_method(Slave *s, int method, PyObject *args) {
    if (!s->bound[method]) {
        if (!s->names[method]) {
            PyErr_SetString(PyExc_NotImplementedError, "this slave has no such method");
            return NULL;
        }
        s->bound[method] = PyObject_GetAttrString(s->slave, s->names[method]);
        if (!s->bound[method]) return NULL;
    }
    return PyObject_CallObject(s->bound[method], args);
}

/* The cached argument tuple (value references,) of this array: borrowed, NULL on a Python error. */
static PyObject *vr_args(Slave *s, const unsigned int vr[], size_t n) {
    for (int i = 0; i < VR_CACHE; i++) {
        VrArgs *e = &s->vrs[i];
        if (e->args && e->n == n && memcmp(e->vr, vr, n * sizeof *vr) == 0) return e->args;
    }
    PyObject *refs = PyTuple_New((Py_ssize_t)n);
    for (size_t i = 0; refs && i < n; i++) {
        PyObject *ref = PyLong_FromUnsignedLong(vr[i]);
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
    VrArgs *e = &s->vrs[s->next_vr];
    s->next_vr = (s->next_vr + 1) % VR_CACHE;
    Py_XDECREF(e->args);
    free(e->vr);
    *e = (VrArgs){n, copy, args};
    return args;
}

/* slave.get_<type>(value references): a new reference to a list or tuple of n items, else NULL. */
static PyObject *get_values(Slave *s, int method, const unsigned int vr[], size_t n) {
    PyObject *args = vr_args(s, vr, n);
    PyObject *result = args ? call_method(s, method, args) : NULL;
    if (result && !((PyList_Check(result) || PyTuple_Check(result)) && (size_t)PyObject_Size(result) == n)) {
        Py_DECREF(result);
        PyErr_Format(PyExc_TypeError, "%s must return a list of %zu values", s->names[method], n);
        return NULL;
    }
    return result;
}

/* Item i of a list or tuple (borrowed). */
static PyObject *item(PyObject *values, size_t i) {
    return PyList_Check(values) ? PyList_GetItem(values, (Py_ssize_t)i) : PyTuple_GetItem(values, (Py_ssize_t)i);
}

/* slave.set_<type>(value references, values), values stolen; 0 with a Python exception on failure. */
static int set_values(Slave *s, int method, const unsigned int vr[], size_t n, PyObject *values) {
    PyObject *args = values ? vr_args(s, vr, n) : NULL;
    PyObject *pair = args ? PyTuple_Pack(2, PyTuple_GetItem(args, 0), values) : NULL;
    PyObject *result = pair ? call_method(s, method, pair) : NULL;
    Py_XDECREF(values);
    Py_XDECREF(pair);
    Py_XDECREF(result);
    return result != NULL;
}

/* A new list from n C values, made by `make` (a new reference or NULL). */
#define LIST_OF(n, make)                                                                                     \
    ({                                                                                                       \
        PyObject *list_ = PyList_New((Py_ssize_t)(n));                                                       \
        for (size_t i = 0; list_ && i < (n); i++) {                                                          \
            PyObject *x_ = (make);                                                                           \
            if (!x_ || PyList_SetItem(list_, (Py_ssize_t)i, x_) < 0) Py_CLEAR(list_);                        \
        }                                                                                                    \
        list_;                                                                                               \
    })

/* The strings of the last get of String values, kept alive until the next one (FMI's rule). */
static const char *keep_string(Slave *s, PyObject *value, size_t i) {
    if (i == 0) {
        Py_XDECREF(s->strings);
        s->strings = PyList_New(0);
    }
    PyObject *bytes = s->strings && PyUnicode_Check(value) ? PyUnicode_AsUTF8String(value) : NULL;
    if (!bytes || PyList_Append(s->strings, bytes) < 0) {
        Py_XDECREF(bytes);
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "a String variable must hold a str");
        return NULL;
    }
    Py_DECREF(bytes);
    return PyBytes_AsString(bytes); /* alive in s->strings */
}

static void forget_methods(Slave *s) {
    for (int i = 0; i < N_METHODS; i++) Py_CLEAR(s->bound[i]);
}

/* A new slave object from the class (replacing any previous one); 0 with a Python exception. */
static int new_slave(Slave *s, int visible) {
    PyObject *kwargs = Py_BuildValue("{s:s,s:s,s:O}", "instance_name", s->name, "resources", s->resources,
                                     "visible", visible ? Py_True : Py_False);
    PyObject *args = kwargs ? PyTuple_New(0) : NULL;
    PyObject *slave = args ? PyObject_Call(s->cls, args, kwargs) : NULL;
    Py_XDECREF(args);
    Py_XDECREF(kwargs);
    if (!slave) return 0;
    PyObject *queue = PyObject_GetAttrString(slave, "log_queue");
    if (!queue || !PyList_Check(queue)) Py_CLEAR(queue); /* a slave without a queue logs nothing */
    PyErr_Clear();
    forget_methods(s);
    Py_XDECREF(s->slave);
    Py_XDECREF(s->queue);
    s->slave = slave;
    s->queue = queue;
    return 1;
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

/* file:///a%20b/resources/ (FMI 2.0) or /a b/resources/ (FMI 3.0) -> /a b/resources; NULL if no memory. */
static char *resource_folder(const char *location) {
    const char *p = location;
    int uri = 0;
    if (strncmp(p, "file://", 7) == 0) p += 7, uri = 1;
    else if (strncmp(p, "file:", 5) == 0) p += 5, uri = 1;
    if (uri && strncmp(p, "localhost/", 10) == 0) p += 9;
    char *out = malloc(strlen(p) + 1), *o = out;
    if (!out) return NULL;
    for (; *p; p++) {
        if (uri && *p == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            *o++ = (char)strtol(hex, NULL, 16);
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    *o = 0;
    for (size_t n = strlen(out); n > 1 && out[n - 1] == '/'; n--) out[n - 1] = 0;
    return out;
}

static void free_slave_memory(Slave *s) {
    free(s->name);
    free(s->resources);
    for (int i = 0; i < VR_CACHE; i++) free(s->vrs[i].vr);
}

/* Release the slave's Python objects (GIL held). */
static void release_slave(Slave *s) {
    forget_methods(s);
    for (int i = 0; i < VR_CACHE; i++) Py_CLEAR(s->vrs[i].args);
    Py_CLEAR(s->slave);
    Py_CLEAR(s->queue);
    Py_CLEAR(s->cls);
    Py_CLEAR(s->strings);
}

/* Set up `s` (owner, emit and names already set): import the slave class named in the resources
   and create the slave. Returns 1, or 0 after logging why (as `function`). Takes the GIL itself. */
static int open_slave(Slave *s, const char *function, const char *name, const char *location, int visible) {
    char text[4400];
    s->name = strdup(name);
    s->resources = location ? resource_folder(location) : NULL;
    if (!s->name || !s->resources) {
        snprintf(text, sizeof text, "%s: %s", function, location ? "out of memory" : "no resource location given");
        emit_text(s, LOG_ERROR, text);
        return 0;
    }
    char *module_name = read_line(s->resources, "slavemodule.txt");
    char *class_name = read_line(s->resources, "slaveclass.txt");
    if (!module_name || !class_name) {
        snprintf(text, sizeof text, "%s: cannot read slavemodule.txt and slaveclass.txt in %s", function,
                 s->resources);
        emit_text(s, LOG_ERROR, text);
        free(module_name);
        free(class_name);
        return 0;
    }
    pthread_once(&python_once, start_python);
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *sys_path = PySys_GetObject("path"); /* borrowed */
    PyObject *folder = PyUnicode_FromString(s->resources);
    if (sys_path && folder && PySequence_Contains(sys_path, folder) == 0) PyList_Insert(sys_path, 0, folder);
    Py_XDECREF(folder);
    PyObject *module = PyErr_Occurred() ? NULL : PyImport_ImportModule(module_name);
    s->cls = module ? PyObject_GetAttrString(module, class_name) : NULL;
    Py_XDECREF(module);
    int ok = s->cls && new_slave(s, visible);
    if (ok) flush_log(s);
    else python_error(s, function);
    if (!ok) release_slave(s);
    PyGILState_Release(gil);
    free(module_name);
    free(class_name);
    return ok;
}

/* FMU states: the slave's state object with the wrapper's mode and time when it was taken. */
typedef struct {
    PyObject *state;
    int mode;
    double time;
} SavedState;

/* A serialised state: this header, then the slave's bytes. */
typedef struct {
    char magic[4]; /* "CRS1" */
    int mode;
    double time;
} StateHeader;

/* The functions below return 1, or 0 with a Python exception set. */

/* Store the slave's state (with mode and time) in *s, allocated if NULL, overwritten if not. */
static int save_state(Slave *py, void **s, int mode, double time) {
    SavedState *saved = *s ? *s : PyMem_Calloc(1, sizeof *saved);
    PyObject *state = saved ? call_method(py, GET_STATE, NULL) : PyErr_NoMemory();
    if (!state) {
        if (saved != *s) PyMem_Free(saved);
        return 0;
    }
    Py_XDECREF(saved->state);
    *saved = (SavedState){state, mode, time};
    *s = saved;
    return 1;
}

static int restore_state(Slave *py, SavedState *saved) {
    PyObject *args = PyTuple_Pack(1, saved->state);
    PyObject *result = args ? call_method(py, SET_STATE, args) : NULL;
    Py_XDECREF(args);
    Py_XDECREF(result);
    return result != NULL;
}

static void free_state(void **s) {
    SavedState *saved = *s;
    Py_XDECREF(saved->state);
    PyMem_Free(saved);
    *s = NULL;
}

/* The serialised state (a new bytes object: header and the slave's bytes), or NULL. */
static PyObject *serialized_state(Slave *py, SavedState *saved) {
    PyObject *args = PyTuple_Pack(1, saved->state);
    PyObject *bytes = args ? call_method(py, TO_BYTES, args) : NULL;
    Py_XDECREF(args);
    if (bytes && !PyBytes_Check(bytes)) {
        Py_CLEAR(bytes);
        PyErr_SetString(PyExc_TypeError, "_fmu_state_to_bytes must return bytes");
    }
    StateHeader header = {{'C', 'R', 'S', '1'}, saved->mode, saved->time};
    PyObject *head = bytes ? PyBytes_FromStringAndSize((const char *)&header, sizeof header) : NULL;
    if (head) PyBytes_ConcatAndDel(&head, bytes);
    else Py_XDECREF(bytes);
    return head;
}

/* A state read back from serialised bytes into *s (allocated if NULL); `modes` are the valid ones. */
static int deserialize_state(Slave *py, const char *data, size_t size, void **s, int modes) {
    StateHeader header;
    if (!data || size < sizeof header || (memcpy(&header, data, sizeof header), memcmp(header.magic, "CRS1", 4)) ||
        !(header.mode & modes)) {
        PyErr_SetString(PyExc_ValueError, "not a serialised state of this FMU");
        return 0;
    }
    SavedState *saved = *s ? *s : PyMem_Calloc(1, sizeof *saved);
    PyObject *args = saved ? Py_BuildValue("(y#)", data + sizeof header, (Py_ssize_t)(size - sizeof header))
                           : PyErr_NoMemory();
    PyObject *state = args ? call_method(py, FROM_BYTES, args) : NULL;
    Py_XDECREF(args);
    if (!state) {
        if (saved != *s) PyMem_Free(saved);
        return 0;
    }
    Py_XDECREF(saved->state);
    *saved = (SavedState){state, header.mode, header.time};
    *s = saved;
    return 1;
}
