/*
 * Model Exchange over the model interface (continuous.h): the mode checks and argument checks, then the
 * model's ContinuousModel. An error puts the instance in its error state; a discard (a state where the
 * derivatives are not finite) leaves it where it is, for the host's solver to try another state.
 */
#include "continuous.h"

#include <math.h>
#include <stdlib.h>

#include "py_repr.h"

#define AFTER_INITIALIZATION (EVENT_MODE | CONTINUOUS_TIME | TERMINATED | FAILED)

static int settled(Instance *c, ModelStatus status) {
    if (status == MODEL_ERROR) c->mode = FAILED;
    return status;
}

int is_model_exchange(Instance *c, const char *function) {
    if (!c) return 0;
    if (c->model_exchange) return 1;
    refuse(c, function, "a Model Exchange function, called on a co-simulation instance");
    return 0;
}

static int checked(Instance *c, const char *function, int modes) {
    return is_model_exchange(c, function) && allowed(c, function, modes);
}

size_t number_of_states(const Instance *c) { return c && c->type->continuous ? c->type->continuous->n_states : 0; }
size_t number_of_indicators(const Instance *c) {
    return c && c->type->continuous ? c->type->continuous->n_indicators : 0;
}

int set_time(Instance *c, const char *function, double time) {
    if (!checked(c, function, EVENT_MODE | CONTINUOUS_TIME)) return MODEL_ERROR;
    if (!isfinite(time)) { /* a bad argument: refused, the instance stays where it is */
        Reporter r = instance_reporter(c, function);
        return report(&r, MODEL_ERROR, "time must be finite, got %s", py_repr(time, (char[REPR_SIZE]){0}));
    }
    c->time = time;
    return MODEL_OK;
}

int enter_event_mode(Instance *c, const char *function, int modes) {
    if (!checked(c, function, modes)) return MODEL_ERROR;
    c->mode = EVENT_MODE;
    return MODEL_OK;
}

int enter_continuous_time_mode(Instance *c, const char *function) {
    if (!checked(c, function, EVENT_MODE)) return MODEL_ERROR;
    c->mode = CONTINUOUS_TIME;
    return MODEL_OK;
}

int completed_integrator_step(Instance *c, const char *function, int *enter_event_mode, int *terminate) {
    if (!checked(c, function, CONTINUOUS_TIME)) return MODEL_ERROR;
    if (!enter_event_mode || !terminate) return refuse(c, function, "NULL output pointer");
    *enter_event_mode = *terminate = 0;
    return MODEL_OK;
}

int update_discrete_states(Instance *c, const char *function, int *terminate, int *states_changed) {
    if (!checked(c, function, EVENT_MODE)) return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    *terminate = 0, *states_changed = 1;
    return settled(c, c->type->continuous->event_update(c->type, c->model, c->time, terminate, &r));
}

/* The checks of an array of the states or event indicators: its length `n` must be `expected`. */
static int array_checks(Instance *c, const char *function, int modes, const void *array, size_t n, size_t expected) {
    if (!checked(c, function, modes)) return 0;
    if (n != expected) {
        refuse(c, function,
               n < expected ? "the array is shorter than the model's" : "the array is longer than the model's");
        return 0;
    }
    if (n && !array) return refuse(c, function, "NULL array"), 0;
    return 1;
}

int get_continuous_states(Instance *c, const char *function, double x[], size_t n) {
    if (!array_checks(c, function, INITIALIZATION | AFTER_INITIALIZATION, x, n, number_of_states(c)))
        return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    return settled(c, c->type->continuous->get_states(c->type, c->model, x, &r));
}

int set_continuous_states(Instance *c, const char *function, const double x[], size_t n) {
    if (!array_checks(c, function, CONTINUOUS_TIME, x, n, number_of_states(c))) return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    return settled(c, c->type->continuous->set_states(c->type, c->model, x, &r));
}

int get_derivatives(Instance *c, const char *function, int modes, double dx[], size_t n) {
    if (!array_checks(c, function, modes, dx, n, number_of_states(c)))
        return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    return settled(c, c->type->continuous->derivatives(c->type, c->model, dx, &r));
}

int get_event_indicators(Instance *c, const char *function, double z[], size_t n) {
    if (!array_checks(c, function, INITIALIZATION | AFTER_INITIALIZATION, z, n, number_of_indicators(c)))
        return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    return settled(c, c->type->continuous->indicators(c->type, c->model, z, &r));
}

int get_nominals(Instance *c, const char *function, int modes, double x[], size_t n) {
    if (!array_checks(c, function, modes, x, n, number_of_states(c))) return MODEL_ERROR;
    for (size_t i = 0; i < n; i++) x[i] = 1.0;
    return MODEL_OK;
}

/* The directional and adjoint derivatives, of a model with a ContinuousModel, in Model Exchange and in co-simulation:
   from initialisation on, and in the error state for diagnosis (FMI 2.0's tables; FMI 3.0 section 2.3 lists them
   in Initialization, Event, Continuous-Time and Step Mode and in Terminated, which an FMU enters after an error).
   Co-simulation's are those of its outputs and state derivatives at the communication point by its states and
   inputs (FMI 2.0 section 2.1.9, Step Mode: the ModelStructure's Outputs, and its Derivatives where it has them). */
#define DERIVATIVE_MODES (INITIALIZATION | RUNNING | TERMINATED | FAILED)

static int derivative_checks(Instance *c, const char *function, const unsigned unknowns[], size_t nu,
                             const unsigned knowns[], size_t nk, const double seed[], double sensitivity[]) {
    if (!c) return 0;
    if (!c->type->continuous) return refuse(c, function, "not supported by this FMU"), 0;
    if (!allowed(c, function, DERIVATIVE_MODES)) return 0;
    if ((nu && (!unknowns || !sensitivity)) || (nk && (!knowns || !seed))) return refuse(c, function, "NULL array"), 0;
    return 1;
}

int directional_derivative(Instance *c, const char *function, const unsigned unknowns[], size_t nu,
                           const unsigned knowns[], size_t nk, const double seed[], double sensitivity[]) {
    if (!derivative_checks(c, function, unknowns, nu, knowns, nk, seed, sensitivity)) return MODEL_ERROR;
    Reporter r = instance_reporter(c, function);
    return settled(c, c->type->continuous->directional(c->type, c->model, unknowns, nu, knowns, nk, seed,
                                                       sensitivity, &r));
}

/* The adjoint, sensitivity[j] = sum over i of seed[i] d unknowns[i] / d knowns[j]: one directional derivative
   along each known (the model's derivatives are forward mode). `seed` has nu values, `sensitivity` nk. */
int adjoint_derivative(Instance *c, const char *function, const unsigned unknowns[], size_t nu,
                       const unsigned knowns[], size_t nk, const double seed[], double sensitivity[]) {
    if (!derivative_checks(c, function, unknowns, nu, knowns, nk, sensitivity, (double *)seed)) return MODEL_ERROR;
    double *column = malloc((nu ? nu : 1) * sizeof *column), one = 1.0;
    if (!column) return refuse(c, function, "out of memory");
    Reporter r = instance_reporter(c, function);
    ModelStatus status = MODEL_OK;
    for (size_t j = 0; j < nk && status <= MODEL_WARNING; j++) {
        status = c->type->continuous->directional(c->type, c->model, unknowns, nu, &knowns[j], 1, &one, column, &r);
        double sum = 0.0;
        for (size_t i = 0; i < nu; i++) sum += seed[i] * column[i];
        sensitivity[j] = sum;
    }
    free(column);
    return settled(c, status);
}
