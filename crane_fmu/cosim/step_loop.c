/*
 * The master's fixed-step loop in C (crane_fmu/cosim/compiled_loop.py compiles and loads it): the
 * same FMI calls, in the same order and with the same arguments, as Master.advance makes one by one
 * through ctypes, so a run gives the same numbers; only the Python call overhead between them goes.
 *
 * The plan is a list of operations made once by the master: the exchange (get/set of Reals, copies
 * between its buffers) and the steps. At each communication point t = start + k*h (k an integer, as
 * in Python): the exchange, a row "t, every output" recorded, then every instance steps.
 *
 * run_calls makes the batch path's other calls (crane_fmu/cosim/reused.py): those that reset the
 * instances and initialise them with a case's parameters, and those that terminate them.
 */
#include <stdbool.h>
#include <stddef.h>

enum { GET_SET_2, GET_SET_3, COPY, DO_STEP_2, DO_STEP_3, CALL, SETUP_2, ENTER_3, SET_STRINGS_2, SET_STRINGS_3,
       SET_INTEGERS_2, SET_INT64S_3 };

typedef struct {
    int kind;
    void *function;        /* the FMI function (none for a copy) */
    void *instance;        /* fmi2Component / fmi3Instance */
    const unsigned *vr;    /* get/set: the value references */
    size_t n;              /* get/set: how many */
    double *values;        /* get/set: the values (set Strings: the strings; Integers, Int64s: those); copy: where to */
    const double *source;  /* copy: from where */
} Operation;

typedef int (*GetSet2)(void *, const unsigned *, size_t, double *);
typedef int (*GetSet3)(void *, const unsigned *, size_t, double *, size_t);
typedef int (*DoStep2)(void *, double, double, int);
typedef int (*DoStep3)(void *, double, double, bool, bool *, bool *, bool *, double *);
typedef int (*Call)(void *);
typedef int (*Setup2)(void *, int, double, double, int, double);
typedef int (*Enter3)(void *, bool, double, double, bool, double);
typedef int (*SetStrings2)(void *, const unsigned *, size_t, const char *const *);
typedef int (*SetStrings3)(void *, const unsigned *, size_t, const char *const *, size_t);
typedef int (*SetIntegers2)(void *, const unsigned *, size_t, const int *);
typedef int (*SetInt64s3)(void *, const unsigned *, size_t, const long long *, size_t);

/* One operation at time t with step h; the calls that set up an experiment (SETUP_2, ENTER_3) take t as its start and
   h as its stop time, as fmpy's setupExperiment and enterInitializationMode pass them (no tolerance, a stop time). */
static int call(const Operation *op, double t, double h) {
    switch (op->kind) {
    case GET_SET_2:
        return ((GetSet2)op->function)(op->instance, op->vr, op->n, op->values);
    case GET_SET_3:
        return ((GetSet3)op->function)(op->instance, op->vr, op->n, op->values, op->n);
    case COPY:
        *op->values = *op->source;
        return 0;
    case DO_STEP_2: /* noSetFMUStatePriorToCurrentPoint = true */
        return ((DoStep2)op->function)(op->instance, t, h, 1);
    case DO_STEP_3: { /* event handling, termination, early return: not used by this master */
        bool event, terminate, early;
        double last;
        return ((DoStep3)op->function)(op->instance, t, h, true, &event, &terminate, &early, &last);
    }
    case CALL: /* reset, enter or exit initialisation (FMI 2.0), terminate: f(instance) */
        return ((Call)op->function)(op->instance);
    case SETUP_2:
        return ((Setup2)op->function)(op->instance, 0, 0.0, t, 1, h);
    case ENTER_3:
        return ((Enter3)op->function)(op->instance, false, 0.0, t, true, h);
    case SET_STRINGS_2:
        return ((SetStrings2)op->function)(op->instance, op->vr, op->n, (const char *const *)op->values);
    case SET_STRINGS_3:
        return ((SetStrings3)op->function)(op->instance, op->vr, op->n, (const char *const *)op->values, op->n);
    case SET_INTEGERS_2:
        return ((SetIntegers2)op->function)(op->instance, op->vr, op->n, (const int *)op->values);
    case SET_INT64S_3:
        return ((SetInt64s3)op->function)(op->instance, op->vr, op->n, (const long long *)op->values, op->n);
    }
    return 3; /* an unknown kind: fmi2Error */
}

/*
 * The communication points first..last-1: at each, the exchange, a row recorded, then the steps (only at points
 * before `step_until`: the last point of a run is exchanged and recorded, not stepped). A row is the time and the
 * outputs named by `keep` (n_keep indices into the master's buffer `outputs`, which the get operations fill);
 * `rows` has room for last - first of them. Returns the rows recorded. When a call's status is worse than warning,
 * stops there: *failed is its operation's index (the exchange's first, then the steps'), *status its status,
 * *failed_at the time; else *failed = -1.
 */
long run_points(const Operation *exchange, size_t n_exchange, const Operation *steps, size_t n_steps, double start,
                double h, long first, long last, long step_until, const double *outputs, const size_t *keep,
                size_t n_keep, double *rows, long *failed, int *status, double *failed_at) {
    *failed = -1;
    for (long k = first; k < last; k++) {
        double t = start + (double)k * h, *row = rows + (size_t)(k - first) * (n_keep + 1);
        for (size_t i = 0; i < n_exchange; i++)
            if ((*status = call(&exchange[i], t, h)) > 1) {
                *failed = (long)i, *failed_at = t;
                return k - first;
            }
        row[0] = t;
        for (size_t i = 0; i < n_keep; i++) row[i + 1] = outputs[keep[i]];
        if (k >= step_until) continue;
        for (size_t i = 0; i < n_steps; i++)
            if ((*status = call(&steps[i], t, h)) > 1) {
                *failed = (long)(n_exchange + i), *failed_at = t;
                return k - first + 1;
            }
    }
    return last - first;
}

/* The operations ops[0..n-1] at (t, h) (the batch path's calls that reset, set up, set parameters, enter and exit
   initialisation, terminate); the index of the first whose status is worse than warning (*status), or -1. */
long run_calls(const Operation *ops, size_t n, double t, double h, int *status) {
    for (size_t i = 0; i < n; i++)
        if ((*status = call(&ops[i], t, h)) > 1) return (long)i;
    return -1;
}
