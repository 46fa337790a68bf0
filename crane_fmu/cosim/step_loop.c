/*
 * The master's fixed-step loop in C (crane_fmu/cosim/compiled_loop.py compiles and loads it): the
 * same FMI calls, in the same order and with the same arguments, as Master.advance makes one by one
 * through ctypes, so a run gives the same numbers; only the Python call overhead between them goes.
 *
 * The plan is a list of operations made once by the master: the exchange (get/set of Reals, copies
 * between its buffers) and the steps. At each communication point t = start + k*h (k an integer, as
 * in Python): the exchange, a row "t, every output" recorded, then every instance steps.
 */
#include <stdbool.h>
#include <stddef.h>
#include <string.h>

enum { GET_SET_2, GET_SET_3, COPY, DO_STEP_2, DO_STEP_3 };

typedef struct {
    int kind;
    void *function;        /* the FMI function (none for a copy) */
    void *instance;        /* fmi2Component / fmi3Instance */
    const unsigned *vr;    /* get/set: the value references */
    size_t n;              /* get/set: how many */
    double *values;        /* get/set: the values; copy: where to */
    const double *source;  /* copy: from where */
} Operation;

typedef int (*GetSet2)(void *, const unsigned *, size_t, double *);
typedef int (*GetSet3)(void *, const unsigned *, size_t, double *, size_t);
typedef int (*DoStep2)(void *, double, double, int);
typedef int (*DoStep3)(void *, double, double, bool, bool *, bool *, bool *, double *);

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
    }
    return 3; /* an unknown kind: fmi2Error */
}

/*
 * Take the steps first..last-1: exchange, record, step. `rows` has room for last - first rows of
 * 1 + n_outputs doubles; `outputs` is the master's buffer the get operations fill. Returns the rows
 * recorded. When a call's status is worse than warning, stops there: *failed is its operation's index
 * (the exchange's first, then the steps'), *status its status, *failed_at the time; else *failed = -1.
 */
long run_steps(const Operation *exchange, size_t n_exchange, const Operation *steps, size_t n_steps, double start,
               double h, long first, long last, const double *outputs, size_t n_outputs, double *rows, long *failed,
               int *status, double *failed_at) {
    *failed = -1;
    for (long k = first; k < last; k++) {
        double t = start + (double)k * h, *row = rows + (size_t)(k - first) * (n_outputs + 1);
        for (size_t i = 0; i < n_exchange; i++)
            if ((*status = call(&exchange[i], t, h)) > 1) {
                *failed = (long)i, *failed_at = t;
                return k - first;
            }
        row[0] = t;
        memcpy(row + 1, outputs, n_outputs * sizeof(double));
        for (size_t i = 0; i < n_steps; i++)
            if ((*status = call(&steps[i], t, h)) > 1) {
                *failed = (long)(n_exchange + i), *failed_at = t;
                return k - first + 1;
            }
    }
    return last - first;
}
