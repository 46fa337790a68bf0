/*
 * The Python side of the FMI wrappers (fmi2_wrapper.c, fmi3_wrapper.c): one pythonfmu (or
 * pythonfmu3) slave object per FMU instance, called through Python's limited API (3.10), so that
 * one compiled wrapper runs with every CPython from 3.10 on.
 *
 * The GIL: every exported FMI function that touches Python takes it once (PyGILState_Ensure) and
 * releases it before returning; the functions here expect it held and never take it again.
 * Hot-path objects are cached per instance: the slave's bound methods and, per value-reference
 * array, the argument tuple holding its value references and the slave's reader and writer of
 * those Reals (slave.real_reader(refs) and slave.real_writer(refs), asked for once: a Real get is
 * then reader(), a set writer(values)).
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
       GET_I32, SET_I32, GET_I64, SET_I64, GET_U64, SET_U64, GET_BOOL, SET_BOOL, GET_STR, SET_STR, READER, WRITER,
       N_METHODS };

/* Statuses: the same numbers in FMI 2.0 and 3.0. */
enum { STATUS_OK = 0, STATUS_DISCARD = 2, STATUS_ERROR = 3 };

/* The modes of the state machine, the same in FMI 2.0 and 3.0 co-simulation without event mode (each
   wrapper names them in its standard's words). After an error the instance is FAILED until it is
   reset or a saved state is set back. */
enum { INSTANTIATED = 1, INITIALIZATION = 2, STEPPING = 4, STEP_DISCARDED = 8, TERMINATED = 16, FAILED = 32 };
#define ANY_MODE (INSTANTIATED | INITIALIZATION | STEPPING | STEP_DISCARDED | TERMINATED | FAILED)
#define GETTABLE (INITIALIZATION | STEPPING | STEP_DISCARDED | TERMINATED | FAILED)
#define SETTABLE (INSTANTIATED | INITIALIZATION | STEPPING)

struct Slave;
typedef void (*Emit)(struct Slave *s, int status, const char *category, const char *text);

#define VR_CACHE 8
typedef struct {
    size_t n;
    unsigned int *vr;
    PyObject *args;      /* (tuple of the value references,) */
    PyObject *reader;    /* slave.real_reader(refs), once asked for */
    PyObject *writer;    /* slave.real_writer(refs), once asked for */
} VrArgs;

/* One FMU instance: the first member of each wrapper's instance struct. */
typedef struct Slave {
    PyObject *cls, *slave, *queue, *strings;
    PyObject *bound[N_METHODS];
    const char *const *names;      /* method names by the enum above, NULL where the slave has none */
    const char *const *mode_names; /* by the bit of each mode */
    VrArgs vrs[VR_CACHE];
    int next_vr;
    struct SavedState **states; /* the FMU states this instance made and has not freed */
    size_t n_states, states_size;
    Emit emit; /* passes a message to the host's logger */
    int logging_on, mode;
    double time; /* the last successful communication point */
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
    s->emit((Slave *)s, status, categories[status >= 0 && status <= 4 ? status : 0], text);
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
    emit_text(s, STATUS_ERROR, buffer);
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
            s->emit((Slave *)s, level >= 0 && level <= 4 ? (int)level : 0, cat ? cat : "logAll", text ? text : "");
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

/* The cache entry of this value-reference array (made if new), NULL on a Python error. */
static VrArgs *vr_entry(Slave *s, const unsigned int vr[], size_t n) {
    for (int i = 0; i < VR_CACHE; i++) {
        VrArgs *e = &s->vrs[i];
        if (e->args && e->n == n && memcmp(e->vr, vr, n * sizeof *vr) == 0) return e;
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
    Py_XDECREF(e->reader);
    Py_XDECREF(e->writer);
    free(e->vr);
    *e = (VrArgs){n, copy, args, NULL, NULL};
    return e;
}

/* *prepared, made by slave.<method>(refs) if not yet: borrowed, NULL on a Python error. */
static PyObject *prepared(Slave *s, PyObject **prepared, int method, PyObject *args) {
    if (!*prepared) *prepared = call_method(s, method, args);
    return *prepared;
}

/* slave.get_<type>(value references), for Reals reader(): a new reference to a list or tuple of n
   items, else NULL. */
static PyObject *get_values(Slave *s, int method, const unsigned int vr[], size_t n) {
    VrArgs *e = vr_entry(s, vr, n);
    PyObject *result = NULL;
    if (e && method == GET_F64) {
        PyObject *reader = prepared(s, &e->reader, READER, e->args);
        result = reader ? PyObject_CallNoArgs(reader) : NULL;
    } else if (e) {
        result = call_method(s, method, e->args);
    }
    if (result && !((PyList_Check(result) || PyTuple_Check(result)) && (size_t)PyObject_Size(result) == n)) {
        Py_DECREF(result);
        PyErr_Format(PyExc_TypeError, "%s must return a list of %zu values",
                     s->names[method == GET_F64 ? READER : method], n);
        return NULL;
    }
    return result;
}

/* Item i of a list or tuple (borrowed). */
static PyObject *item(PyObject *values, size_t i) {
    return PyList_Check(values) ? PyList_GetItem(values, (Py_ssize_t)i) : PyTuple_GetItem(values, (Py_ssize_t)i);
}

/* slave.set_<type>(value references, values), for Reals writer(values); values stolen; 0 with a
   Python exception on failure. */
static int set_values(Slave *s, int method, const unsigned int vr[], size_t n, PyObject *values) {
    VrArgs *e = values ? vr_entry(s, vr, n) : NULL;
    PyObject *result = NULL;
    if (e && method == SET_F64) {
        PyObject *writer = prepared(s, &e->writer, WRITER, e->args);
        result = writer ? PyObject_CallFunctionObjArgs(writer, values, NULL) : NULL;
    } else if (e) {
        PyObject *pair = PyTuple_Pack(2, PyTuple_GetItem(e->args, 0), values);
        result = pair ? call_method(s, method, pair) : NULL;
        Py_XDECREF(pair);
    }
    Py_XDECREF(values);
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

/* Forget what belongs to the slave object: its bound methods, readers and writers. */
static void forget_methods(Slave *s) {
    for (int i = 0; i < N_METHODS; i++) Py_CLEAR(s->bound[i]);
    for (int i = 0; i < VR_CACHE; i++) {
        Py_CLEAR(s->vrs[i].reader);
        Py_CLEAR(s->vrs[i].writer);
    }
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
    free(s->states);
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

/* Set up the instance `s` (emit, names and mode names already set): import the slave class named
   in the resources and create the slave. Returns 1, or 0 after logging why. Takes the GIL itself. */
static int open_instance(Slave *s, const char *function, const char *name, const char *location, int visible,
                         int logging_on) {
    char text[4400];
    s->mode = INSTANTIATED;
    s->logging_on = logging_on;
    s->name = strdup(name);
    s->resources = location ? resource_folder(location) : NULL;
    if (!s->name || !s->resources) {
        snprintf(text, sizeof text, "%s: %s", function, location ? "out of memory" : "no resource location given");
        emit_text(s, STATUS_ERROR, text);
        return 0;
    }
    char *module_name = read_line(s->resources, "slavemodule.txt");
    char *class_name = read_line(s->resources, "slaveclass.txt");
    if (!module_name || !class_name) {
        snprintf(text, sizeof text, "%s: cannot read slavemodule.txt and slaveclass.txt in %s", function,
                 s->resources);
        emit_text(s, STATUS_ERROR, text);
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

/* ---- The FMI instance, the same in both versions: the state machine, the calls, FMU states. ---- */

static const char *mode_name(const Slave *s) { return s->mode_names[__builtin_ctz((unsigned)s->mode)]; }

/* The state machine: may `function` be called in the instance's mode? If not, say so. */
static int allowed(Slave *s, const char *function, int modes) {
    if (!s) return 0;
    if (s->mode & modes) return 1;
    char text[256];
    snprintf(text, sizeof text, "%s must not be called when the instance is %s", function, mode_name(s));
    emit_text(s, STATUS_ERROR, text);
    return 0;
}

/* Refuse a call with bad arguments: an error and the reason, the mode unchanged. */
static int refuse(Slave *s, const char *function, const char *why) {
    char text[512];
    snprintf(text, sizeof text, "%s: %s", function, why);
    if (s) emit_text(s, STATUS_ERROR, text);
    return STATUS_ERROR;
}

/* The status of a Python call (ok: it succeeded); a failure is logged and puts the instance in error. */
static int finish(Slave *s, const char *function, int ok) {
    if (ok) {
        flush_log(s);
        return STATUS_OK;
    }
    log_failure(s, function);
    s->mode = FAILED;
    return STATUS_ERROR;
}

/* slave.<method>() in one of `modes`, the GIL taken once; on success the mode becomes `next`. */
static int simple_call(Slave *s, const char *function, int modes, int method, int next) {
    if (!allowed(s, function, modes)) return STATUS_ERROR;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = call_method(s, method, NULL);
    int status = finish(s, function, result != NULL);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == STATUS_OK) s->mode = next;
    return status;
}

static int set_logging(Slave *s, const char *function, int on) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    s->logging_on = on;
    return STATUS_OK;
}

/* A fresh slave object: back to instantiated. */
static int reset(Slave *s, const char *function) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    PyGILState_STATE gil = PyGILState_Ensure();
    int status = finish(s, function, new_slave(s, 0));
    PyGILState_Release(gil);
    if (status == STATUS_OK) s->mode = INSTANTIATED;
    return status;
}

/* slave.do_step(t, h): true is a step taken, false a step discarded (the slave logged why). */
static int do_step(Slave *s, const char *function, double t, double h) {
    if (!allowed(s, function, STEPPING)) return STATUS_ERROR;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dd)", t, h);
    PyObject *result = args ? call_method(s, DO_STEP, args) : NULL;
    int done = result ? PyObject_IsTrue(result) : -1;
    Py_XDECREF(args);
    Py_XDECREF(result);
    int status = finish(s, function, done >= 0);
    PyGILState_Release(gil);
    if (status == STATUS_OK && done) s->time = t + h;
    else if (status == STATUS_OK) s->mode = STEP_DISCARDED, status = STATUS_DISCARD;
    return status;
}

/* What every get and set checks first: the instance's mode, then an empty call (ok) and NULL arrays
   (refused). GO_ON when the values are to be moved, else the status to return. */
enum { GO_ON = -1 };
static int first_checks(Slave *s, const char *function, int modes, size_t n, const void *vr, const void *v) {
    if (!allowed(s, function, modes)) return STATUS_ERROR;
    if (n == 0) return STATUS_OK;
    if (!vr || !v) return refuse(s, function, "NULL array");
    return GO_ON;
}

/* The body of an FMI get function: slave.<method>(value references), item x of the result
   converted into v[i] by `convert`. Evaluates to the status. */
#define GET_VALUES(instance, function, method, vr, n, v, convert)                                            \
    ({                                                                                                       \
        Slave *s = (instance);                                                                               \
        int status_ = first_checks(s, function, GETTABLE, n, vr, v);                                         \
        if (status_ == GO_ON) {                                                                              \
            PyGILState_STATE gil_ = PyGILState_Ensure();                                                     \
            PyObject *values_ = get_values(s, method, vr, n);                                                \
            for (size_t i = 0; values_ && i < (n); i++) {                                                    \
                PyObject *x = item(values_, i);                                                              \
                convert;                                                                                     \
                if (PyErr_Occurred()) Py_CLEAR(values_);                                                     \
            }                                                                                                \
            status_ = finish(s, function, values_ != NULL);                                                  \
            Py_XDECREF(values_);                                                                             \
            PyGILState_Release(gil_);                                                                        \
        }                                                                                                    \
        status_;                                                                                             \
    })

/* The body of an FMI set function: slave.<method>(value references, the values made by `make`). */
#define SET_VALUES(instance, function, method, vr, n, v, make)                                               \
    ({                                                                                                       \
        Slave *s = (instance);                                                                               \
        int status_ = first_checks(s, function, SETTABLE, n, vr, v);                                         \
        if (status_ == GO_ON) {                                                                              \
            PyGILState_STATE gil_ = PyGILState_Ensure();                                                     \
            status_ = finish(s, function, set_values(s, method, vr, n, LIST_OF(n, make)));                   \
            PyGILState_Release(gil_);                                                                        \
        }                                                                                                    \
        status_;                                                                                             \
    })

/* FMU states: the slave's state object with the instance's mode and time when it was taken. */
typedef struct SavedState {
    PyObject *state;
    int mode;
    double time;
} SavedState;

/* An instance knows the FMU states it made: any other pointer a host hands it (another instance's
   state, a freed one, garbage, or the state where its address belongs) is refused, never used. */
#define NOT_OURS "not an FMU state of this instance (or one already freed)"
static int is_own_state(const Slave *s, const void *state) {
    for (size_t i = 0; state && i < s->n_states; i++)
        if (s->states[i] == state) return 1;
    return 0;
}

/* Remember a new state; 0 if out of memory. */
static int keep_state(Slave *s, SavedState *state) {
    if (s->n_states == s->states_size) {
        size_t size = s->states_size ? 2 * s->states_size : 8;
        SavedState **grown = realloc(s->states, size * sizeof *grown);
        if (!grown) return 0;
        s->states = grown, s->states_size = size;
    }
    s->states[s->n_states++] = state;
    return 1;
}

/* Forget and free a state (GIL held). */
static void drop_state(Slave *s, SavedState *state) {
    for (size_t i = 0; i < s->n_states; i++)
        if (s->states[i] == state) s->states[i] = s->states[--s->n_states];
    Py_XDECREF(state->state);
    PyMem_Free(state);
}

/* Keep the slave's state `object` (a new reference; NULL after a Python error) with `mode` and
   `time` in `saved`, which is *state or, if new, becomes *state and one of the instance's states.
   1 if stored, else 0 with a Python exception set (a new `saved` is freed). */
static int store_state(Slave *s, void **state, SavedState *saved, PyObject *object, int mode, double time) {
    if (object && saved != *state && !keep_state(s, saved)) {
        Py_CLEAR(object);
        PyErr_NoMemory();
    }
    if (!object) {
        if (saved != *state) PyMem_Free(saved);
        return 0;
    }
    Py_XDECREF(saved->state);
    *saved = (SavedState){object, mode, time};
    *state = saved;
    return 1;
}

/* The check of a host's `FMUstate *` argument: NULL (refused), the state itself where its address
   belongs, or an address holding neither NULL (when `null_ok`) nor one of this instance's states.
   Returns NULL if the pointer may be used, else the reason. */
static const char *bad_state_address(const Slave *s, void **state, int null_ok) {
    if (!state) return "NULL state pointer";
    if (is_own_state(s, state)) return "given an FMU state where the address of one belongs";
    if (!*state) return null_ok ? NULL : "NULL state";
    return is_own_state(s, *state) ? NULL : NOT_OURS;
}

/* A serialised state: this header, then the slave's bytes. */
typedef struct {
    char magic[4]; /* "CRS1" */
    int mode;
    double time;
} StateHeader;

/* Store the slave's state in *state, allocated if NULL, overwritten if not. */
static int get_fmu_state(Slave *s, const char *function, void **state) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    const char *bad = bad_state_address(s, state, 1);
    if (bad) return refuse(s, function, bad);
    PyGILState_STATE gil = PyGILState_Ensure();
    SavedState *saved = *state ? *state : PyMem_Calloc(1, sizeof *saved);
    PyObject *object = saved ? call_method(s, GET_STATE, NULL) : PyErr_NoMemory();
    int status = finish(s, function, store_state(s, state, saved, object, s->mode, s->time));
    PyGILState_Release(gil);
    return status;
}

/* Set a saved state back, with the mode and time it was taken in. */
static int set_fmu_state(Slave *s, const char *function, SavedState *saved) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    if (!saved) return refuse(s, function, "NULL state");
    if (!is_own_state(s, saved)) return refuse(s, function, NOT_OURS);
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = PyTuple_Pack(1, saved->state);
    PyObject *result = args ? call_method(s, SET_STATE, args) : NULL;
    int status = finish(s, function, result != NULL);
    Py_XDECREF(args);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == STATUS_OK) s->mode = saved->mode, s->time = saved->time;
    return status;
}

static int free_fmu_state(Slave *s, const char *function, void **state) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    const char *bad = bad_state_address(s, state, 1);
    if (bad) return refuse(s, function, bad);
    if (!*state) return STATUS_OK;
    PyGILState_STATE gil = PyGILState_Ensure();
    drop_state(s, *state);
    PyGILState_Release(gil);
    *state = NULL;
    return STATUS_OK;
}

/* The serialised state (a new bytes object: header and the slave's bytes), or NULL. GIL held. */
static PyObject *serialized_state(Slave *s, SavedState *saved) {
    PyObject *args = PyTuple_Pack(1, saved->state);
    PyObject *bytes = args ? call_method(s, TO_BYTES, args) : NULL;
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

/* The serialised state's size into *size, and, with `out`, the state itself into out[0..size). */
static int serialize_fmu_state(Slave *s, const char *function, SavedState *saved, char *out, size_t *size) {
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    if (!saved || !size) return refuse(s, function, "NULL state, size or buffer");
    if (!is_own_state(s, saved)) return refuse(s, function, NOT_OURS);
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = serialized_state(s, saved);
    int status = finish(s, function, bytes != NULL);
    if (bytes && out && (size_t)PyBytes_Size(bytes) > *size) status = refuse(s, function, "the buffer is too small");
    else if (bytes && out) memcpy(out, PyBytes_AsString(bytes), (size_t)PyBytes_Size(bytes));
    else if (bytes) *size = (size_t)PyBytes_Size(bytes);
    Py_XDECREF(bytes);
    PyGILState_Release(gil);
    return status;
}

/* A state read back from serialised bytes into *state (allocated if NULL). */
static int deserialize_fmu_state(Slave *s, const char *function, const char *data, size_t size, void **state) {
    StateHeader header;
    if (!allowed(s, function, ANY_MODE)) return STATUS_ERROR;
    const char *bad = bad_state_address(s, state, 1);
    if (bad) return refuse(s, function, bad);
    if (!data || size < sizeof header || (memcpy(&header, data, sizeof header), memcmp(header.magic, "CRS1", 4)) ||
        !(header.mode & ANY_MODE) || __builtin_popcount((unsigned)header.mode) != 1)
        return refuse(s, function, "not a serialised state of this FMU");
    PyGILState_STATE gil = PyGILState_Ensure();
    SavedState *saved = *state ? *state : PyMem_Calloc(1, sizeof *saved);
    PyObject *args = saved ? Py_BuildValue("(y#)", data + sizeof header, (Py_ssize_t)(size - sizeof header))
                           : PyErr_NoMemory();
    PyObject *object = args ? call_method(s, FROM_BYTES, args) : NULL;
    Py_XDECREF(args);
    int status = finish(s, function, store_state(s, state, saved, object, header.mode, header.time));
    PyGILState_Release(gil);
    return status;
}

static void free_instance(Slave *s) {
    if (!s) return;
    PyGILState_STATE gil = PyGILState_Ensure();
    while (s->n_states) drop_state(s, s->states[0]); /* states the host did not free */
    release_slave(s);
    PyGILState_Release(gil);
    free_slave_memory(s);
    free(s); /* the wrapper's instance, whose first member `s` is */
}
