/*
 * The FMI-version-independent part of the frameworks: instances, the state machine, FMU states.
 * Every allocation is checked; a failed one is an error with a message, never a crash.
 */
#include "framework.h"
#include "py_repr.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const CATEGORIES[] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError"};

int instance_log(Instance *c, ModelStatus status, const char *function, const char *message) {
    if (!c || (status == MODEL_OK && !c->logging_on)) return status;
    char text[1024];
    snprintf(text, sizeof text, "%s: %s", function, message);
    c->host_log(c, status, CATEGORIES[status], status == MODEL_ERROR ? text : message); /* as the Python FMU logs */
    return status;
}

static void log_for_model(void *host, ModelStatus status, const char *function, const char *message) {
    instance_log(host, status, function, message);
}

ModelStatus report(const Reporter *r, ModelStatus status, const char *format, ...) {
    char text[1024];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    if (r && r->log) r->log(r->host, status, r->function, text);
    return status;
}

Reporter reporter(Instance *c, const char *function) { return (Reporter){log_for_model, c, function}; }

int refuse(Instance *c, const char *function, const char *why) { return instance_log(c, MODEL_ERROR, function, why); }

static const char *mode_name(const Instance *c) {
    int bit = 0;
    while (bit < 5 && !(c->mode & (1 << bit))) bit++;
    return c->mode_names[bit];
}

int allowed(Instance *c, const char *function, int modes) {
    if (!c) return 0;
    if (c->mode & modes) return 1;
    char text[512];
    snprintf(text, sizeof text, "%s must not be called when the instance is %s", function, mode_name(c));
    c->host_log(c, MODEL_ERROR, CATEGORIES[MODEL_ERROR], text);
    return 0;
}

/* The status of a model call; an error puts the instance in its error state. */
static int settle(Instance *c, ModelStatus status, int next_mode) {
    if (status == MODEL_ERROR) c->mode = FAILED;
    else if (status == MODEL_DISCARD) c->mode = STEP_DISCARDED;
    else if (next_mode) c->mode = next_mode;
    return status;
}

Instance *instance_new(const char *function, const char *name, const char *const *mode_names, HostLog host_log,
                       void *host, int logging_on) {
    Instance *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    *c = (Instance){.mode = INSTANTIATED, .logging_on = logging_on, .mode_names = mode_names, .host_log = host_log,
                    .host = host};
    c->name = malloc(strlen(name) + 1);
    c->model = calloc(1, MODEL_SIZE);
    if (!c->name || !c->model) {
        refuse(c, function, "out of memory");
        instance_free(c);
        return NULL;
    }
    strcpy(c->name, name);
    model_defaults(c->model);
    return c;
}

void instance_free(Instance *c) {
    if (!c) return;
    for (size_t i = 0; i < c->n_states; i++) free(c->states[i]); /* states the host did not free */
    free(c->states);
    free(c->model);
    free(c->name);
    free(c);
}

int enter_initialization(Instance *c, const char *function, double start) {
    if (!allowed(c, function, INSTANTIATED)) return MODEL_ERROR;
    c->time = start;
    c->mode = INITIALIZATION;
    return MODEL_OK;
}

int exit_initialization(Instance *c, const char *function) {
    if (!allowed(c, function, INITIALIZATION)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    return settle(c, model_initialize(c->model, &r), STEPPING);
}

int terminate(Instance *c, const char *function) {
    if (!allowed(c, function, STEPPING | STEP_DISCARDED)) return MODEL_ERROR;
    c->mode = TERMINATED;
    return MODEL_OK;
}

int reset(Instance *c, const char *function) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    model_defaults(c->model);
    c->mode = INSTANTIATED;
    c->time = 0.0;
    return MODEL_OK;
}

int get_reals(Instance *c, const char *function, const unsigned vr[], size_t n, double v[]) {
    if (!allowed(c, function, GETTABLE)) return MODEL_ERROR;
    if (n == 0) return MODEL_OK;
    if (!vr || !v) return refuse(c, function, "NULL array");
    Reporter r = reporter(c, function);
    return settle(c, model_get_reals(c->model, vr, n, v, &r), 0);
}

int set_reals(Instance *c, const char *function, const unsigned vr[], size_t n, const double v[]) {
    if (!allowed(c, function, SETTABLE)) return MODEL_ERROR;
    if (n == 0) return MODEL_OK;
    if (!vr || !v) return refuse(c, function, "NULL array");
    Reporter r = reporter(c, function);
    return settle(c, model_set_reals(c->model, vr, n, v, c->mode != STEPPING, &r), 0);
}

int get_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *v[]) {
    if (MODEL_N_STRINGS == 0) return no_such_values(c, function, GETTABLE, n);
    if (!allowed(c, function, GETTABLE)) return MODEL_ERROR;
    if (n == 0) return MODEL_OK;
    if (!vr || !v) return refuse(c, function, "NULL array");
    Reporter r = reporter(c, function);
    return settle(c, model_get_strings(c->model, vr, n, v, &r), 0);
}

int set_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *const v[]) {
    if (MODEL_N_STRINGS == 0) return no_such_values(c, function, SETTABLE, n);
    if (!allowed(c, function, SETTABLE)) return MODEL_ERROR;
    if (n == 0) return MODEL_OK;
    if (!vr || !v) return refuse(c, function, "NULL array");
    Reporter r = reporter(c, function);
    return settle(c, model_set_strings(c->model, vr, n, v, c->mode != STEPPING, &r), 0);
}

int no_such_values(Instance *c, const char *function, int modes, size_t n) {
    if (!allowed(c, function, modes)) return MODEL_ERROR;
    /* a value of a type the FMU has none of is an error, as in the Python FMU (the instance is then in error) */
    return n == 0 ? MODEL_OK : settle(c, refuse(c, function, "this FMU has no variables of this type"), 0);
}

int do_step(Instance *c, const char *function, double t, double h) {
    if (!allowed(c, function, STEPPING)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    ModelStatus status = h > 0 && isfinite(h) ? model_do_step(c->model, t, h, &r) /* the rule of runtime.py */
        : report(&r, MODEL_ERROR, "communication step must be > 0 and finite, got %s", py_repr(h, (char[REPR_SIZE]){0}));
    status = settle(c, status, 0);
    if (status <= MODEL_WARNING) c->time = t + h;
    return status;
}

/* FMU states: a header (mode, time) and a copy of the model, in one block. */
#define STATE_SIZE (sizeof(StateHeader) + MODEL_SIZE)
static const char *const NOT_OURS = "not an FMU state of this instance (made by another, already freed, or not a "
                                    "state at all)";

static int is_own_state(const Instance *c, const void *state) {
    for (size_t i = 0; i < c->n_states; i++)
        if (c->states[i] == state) return 1;
    return 0;
}

/* A new state block, remembered as this instance's; NULL when out of memory. */
static void *new_state(Instance *c) {
    if (c->n_states == c->states_size) {
        size_t size = c->states_size ? 2 * c->states_size : 4;
        void **states = realloc(c->states, size * sizeof *states);
        if (!states) return NULL;
        c->states = states, c->states_size = size;
    }
    void *state = malloc(STATE_SIZE);
    if (state) c->states[c->n_states++] = state;
    return state;
}

static void write_state(Instance *c, void *state) {
    StateHeader header = {{'C', 'R', 'N', '1'}, c->mode, c->time};
    memcpy(state, &header, sizeof header);
    memcpy((char *)state + sizeof header, c->model, MODEL_SIZE);
}

int get_fmu_state(Instance *c, const char *function, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state) return refuse(c, function, "NULL state pointer");
    if (*state && !is_own_state(c, *state)) return refuse(c, function, NOT_OURS);
    void *target = *state ? *state : new_state(c);
    if (!target) return refuse(c, function, "out of memory");
    write_state(c, target);
    *state = target;
    return MODEL_OK;
}

int set_fmu_state(Instance *c, const char *function, void *state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state || !is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    StateHeader header;
    memcpy(&header, state, sizeof header);
    memcpy(c->model, (char *)state + sizeof header, MODEL_SIZE);
    c->mode = header.mode, c->time = header.time;
    return MODEL_OK;
}

int free_fmu_state(Instance *c, const char *function, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state) return refuse(c, function, "NULL state pointer");
    if (!*state) return MODEL_OK;
    for (size_t i = 0; i < c->n_states; i++)
        if (c->states[i] == *state) {
            free(*state);
            c->states[i] = c->states[--c->n_states];
            *state = NULL;
            return MODEL_OK;
        }
    return refuse(c, function, NOT_OURS);
}

int serialized_size(Instance *c, const char *function, void *state, size_t *size) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!size) return refuse(c, function, "NULL size");
    if (!is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    *size = STATE_SIZE;
    return MODEL_OK;
}

int serialize_fmu_state(Instance *c, const char *function, void *state, unsigned char out[], size_t size) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!out) return refuse(c, function, "NULL buffer");
    if (!is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    if (size < STATE_SIZE) return refuse(c, function, "the buffer is too small");
    memcpy(out, state, STATE_SIZE);
    return MODEL_OK;
}

int deserialize_fmu_state(Instance *c, const char *function, const unsigned char data[], size_t size, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state) return refuse(c, function, "NULL state pointer");
    if (*state && !is_own_state(c, *state)) return refuse(c, function, NOT_OURS);
    StateHeader header;
    if (!data || size != STATE_SIZE || (memcpy(&header, data, sizeof header), memcmp(header.magic, "CRN1", 4)) ||
        !(header.mode & ANY_MODE) || (header.mode & (header.mode - 1)) != 0)
        return refuse(c, function, "not a serialised state of this FMU (of this build)");
    void *target = *state ? *state : new_state(c);
    if (!target) return refuse(c, function, "out of memory");
    memcpy(target, data, STATE_SIZE);
    *state = target;
    return MODEL_OK;
}
