/*
 * The FMI-version-independent part of the frameworks: instances, the state machine, the argument checks, FMU
 * states. Every allocation is checked; a failed one is an error with a message, never a crash.
 */
#include "instance.h"
#include "py_repr.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const CATEGORIES[] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError"};

int instance_log(Instance *c, ModelStatus status, const char *function, const char *message) {
    if (!c || (status == MODEL_OK && !c->logging_on)) return status;
    char text[4400];
    if (status == MODEL_ERROR) snprintf(text, sizeof text, "%s: %s", function, message);
    c->host_log(c, status, CATEGORIES[status], status == MODEL_ERROR ? text : message);
    return status;
}

static void log_for_model(void *host, ModelStatus status, const char *function, const char *message) {
    instance_log(host, status > MODEL_ERROR ? MODEL_ERROR : status, function, message);
}

ModelStatus report(const Reporter *r, ModelStatus status, const char *format, ...) {
    char text[4096];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    if (r && r->log) r->log(r->host, status, r->function, text);
    return status;
}

static Reporter reporter(Instance *c, const char *function) { return (Reporter){log_for_model, c, function}; }
Reporter instance_reporter(Instance *c, const char *function) { return reporter(c, function); }

int refuse(Instance *c, const char *function, const char *why) { return instance_log(c, MODEL_ERROR, function, why); }

static const char *mode_name(const Instance *c) {
    int bit = 0;
    while (bit < 7 && !(c->mode & (1 << bit))) bit++;
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

/* The status of a model call; an error puts the instance in its error state, a discard in the discarded one
   (co-simulation's: Model Exchange's host retries with another state). */
static int settle(Instance *c, ModelStatus status, int next_mode) {
    if (status == MODEL_ERROR) c->mode = FAILED;
    else if (status == MODEL_DISCARD && !c->model_exchange) c->mode = STEP_DISCARDED;
    else if (next_mode) c->mode = next_mode;
    return status;
}

/* file:///a%20b/resources/ (FMI 2.0) or /a b/resources/ (FMI 3.0) -> /a b/resources; NULL if out of memory. */
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

/* Whether the host's GUID / instantiation token is another build's: the model's own token, or (a model shared by
   FMUs, the Python one) the first line of resources/token.txt that the build writes. No token given, or none to
   compare with: not differing. */
int token_differs(const ModelType *type, const char *token, const char *location) {
    if (!token) return 0;
    if (type->token) return strcmp(token, type->token) != 0;
    char *resources = location ? resource_folder(location) : NULL;
    if (!resources) return 0;
    size_t size = strlen(resources) + sizeof "/token.txt";
    char *path = malloc(size);
    FILE *f = NULL;
    if (path) snprintf(path, size, "%s/token.txt", resources), f = fopen(path, "r");
    free(path);
    free(resources);
    if (!f) return 0;
    char line[256] = {0};
    if (!fgets(line, sizeof line, f)) line[0] = 0;
    fclose(f);
    line[strcspn(line, "\r\n")] = 0;
    return line[0] && strcmp(token, line) != 0;
}

static Instance *new_instance(const char *function, const ModelType *type, const char *name, const char *location,
                              int visible, int logging_on, const char *const *mode_names, HostLog host_log,
                              void *host, int model_exchange) {
    Instance *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    *c = (Instance){.mode = INSTANTIATED, .logging_on = logging_on, .type = type, .mode_names = mode_names,
                    .host_log = host_log, .host = host, .model_exchange = model_exchange};
    c->name = malloc(strlen(name) + 1);
    char *resources = location ? resource_folder(location) : NULL;
    c->model = calloc(1, type->size(type));
    if (!c->name || !c->model || (location && !resources)) {
        free(resources);
        refuse(c, function, "out of memory");
        instance_free(c);
        return NULL;
    }
    strcpy(c->name, name);
    c->at = (Instantiation){c->name, resources, visible, model_exchange};
    Reporter r = reporter(c, function);
    if (type->instantiate(type, c->model, &c->at, &r) > MODEL_WARNING) {
        instance_free(c);
        return NULL;
    }
    return c;
}

Instance *instance_new(const char *function, const ModelType *type, const char *name, const char *location,
                       int visible, int logging_on, const char *const *mode_names, HostLog host_log, void *host) {
    return new_instance(function, type, name, location, visible, logging_on, mode_names, host_log, host, 0);
}

Instance *instance_new_model_exchange(const char *function, const ModelType *type, const char *name,
                                      const char *location, int visible, int logging_on,
                                      const char *const *mode_names, HostLog host_log, void *host) {
    return new_instance(function, type, name, location, visible, logging_on, mode_names, host_log, host, 1);
}

/* ---- FMU states: a saved model (its block copied, or its own object) with the instance's mode and time ---- */

struct SavedState {
    int mode;
    double time;
    void *model; /* a copy of the model's block, or what type->states->save made */
};

static int is_own_state(const Instance *c, const void *state) {
    for (size_t i = 0; state && i < c->n_states; i++)
        if (c->states[i] == state) return 1;
    return 0;
}

static void drop_state(Instance *c, SavedState *state) {
    for (size_t i = 0; i < c->n_states; i++)
        if (c->states[i] == state) c->states[i] = c->states[--c->n_states];
    if (c->type->states && state->model) c->type->states->discard(c->type, state->model);
    else free(state->model);
    free(state);
}

void instance_free(Instance *c) {
    if (!c) return;
    while (c->n_states) drop_state(c, c->states[0]); /* states the host did not free */
    free(c->states);
    if (c->model && c->type->free) c->type->free(c->type, c->model);
    free(c->model);
    free((char *)c->at.resources);
    free(c->name);
    free(c);
}

int set_logging(Instance *c, const char *function, int on) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    c->logging_on = on;
    return MODEL_OK;
}

/* ---- the calls: the mode checked, the arguments checked, the model called, its status settled ---- */

int setup_experiment(Instance *c, const char *function, const Experiment *e) {
    if (!allowed(c, function, INSTANTIATED)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    int status = settle(c, c->type->setup_experiment ? c->type->setup_experiment(c->type, c->model, e, &r) : MODEL_OK, 0);
    if (status <= MODEL_WARNING) c->time = e->start;
    return status;
}

int enter_initialization(Instance *c, const char *function) {
    if (!allowed(c, function, INSTANTIATED)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    return settle(c, c->type->enter_initialization ? c->type->enter_initialization(c->type, c->model, &r) : MODEL_OK,
                  INITIALIZATION);
}

int exit_initialization(Instance *c, const char *function) {
    if (!allowed(c, function, INITIALIZATION)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    return settle(c, c->type->exit_initialization(c->type, c->model, &r), c->model_exchange ? EVENT_MODE : STEPPING);
}

int terminate(Instance *c, const char *function) {
    if (!allowed(c, function, RUNNING)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    return settle(c, c->type->terminate ? c->type->terminate(c->type, c->model, &r) : MODEL_OK, TERMINATED);
}

int reset(Instance *c, const char *function) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (c->type->free) c->type->free(c->type, c->model);
    memset(c->model, 0, c->type->size(c->type));
    c->time = 0.0;
    Reporter r = reporter(c, function);
    return settle(c, c->type->instantiate(c->type, c->model, &c->at, &r), INSTANTIATED);
}

/* What every get and set checks first: the mode, then an empty call (ok) and NULL arrays (refused). GO_ON when
   the values are to be moved, else the status to return. */
enum { GO_ON = -1 };
static int first_checks(Instance *c, const char *function, int modes, size_t n, const void *vr, const void *v) {
    if (!allowed(c, function, modes)) return MODEL_ERROR;
    if (n == 0) return MODEL_OK;
    if (!vr || !v) return refuse(c, function, "NULL array");
    return GO_ON;
}

int get_reals(Instance *c, const char *function, const unsigned vr[], size_t n, double v[]) {
    int status = first_checks(c, function, GETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status : settle(c, c->type->get_reals(c->type, c->model, vr, n, v, &r), 0);
}

/* Parameters may change until initialisation ends. */
static int fixed_allowed(const Instance *c) { return (c->mode & (INSTANTIATED | INITIALIZATION)) != 0; }

int set_reals(Instance *c, const char *function, const unsigned vr[], size_t n, const double v[]) {
    int status = first_checks(c, function, SETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status
                           : settle(c, c->type->set_reals(c->type, c->model, vr, n, v, fixed_allowed(c), &r), 0);
}

int get_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *v[]) {
    if (!c || !c->type->get_strings) return no_such_values(c, function, GETTABLE, n);
    int status = first_checks(c, function, GETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status : settle(c, c->type->get_strings(c->type, c->model, vr, n, v, &r), 0);
}

int set_strings(Instance *c, const char *function, const unsigned vr[], size_t n, const char *const v[]) {
    if (!c || !c->type->set_strings) return no_such_values(c, function, SETTABLE, n);
    int status = first_checks(c, function, SETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status
                           : settle(c, c->type->set_strings(c->type, c->model, vr, n, v, fixed_allowed(c), &r), 0);
}

int get_integers(Instance *c, const char *function, const unsigned vr[], size_t n, long long v[]) {
    if (!c || !c->type->get_integers) return no_such_values(c, function, GETTABLE, n);
    int status = first_checks(c, function, GETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status : settle(c, c->type->get_integers(c->type, c->model, vr, n, v, &r), 0);
}

int set_integers(Instance *c, const char *function, const unsigned vr[], size_t n, const long long v[]) {
    if (!c || !c->type->set_integers) return no_such_values(c, function, SETTABLE, n);
    int status = first_checks(c, function, SETTABLE, n, vr, v);
    Reporter r = reporter(c, function);
    return status != GO_ON ? status
                           : settle(c, c->type->set_integers(c->type, c->model, vr, n, v, fixed_allowed(c), &r), 0);
}

int no_such_values(Instance *c, const char *function, int modes, size_t n) {
    if (!allowed(c, function, modes)) return MODEL_ERROR;
    return n == 0 ? MODEL_OK : settle(c, refuse(c, function, "this FMU has no variables of this type"), 0);
}

/* A communication step this short is a host's rounding (OMSimulator ends a run with the remainder of its summed
   time, 1.03e-13 s after 10,000 steps of 1 ms): no step, time moves on. runtime.py's ROUNDING_STEP, the one-FMU
   systems' 1e-6 of their 1 ms system step (system.c). */
#define ROUNDING_STEP 1e-9

int do_step(Instance *c, const char *function, double t, double h) {
    if (!allowed(c, function, STEPPING)) return MODEL_ERROR;
    Reporter r = reporter(c, function);
    ModelStatus status = !(h > 0 && isfinite(h))
        ? report(&r, MODEL_ERROR, "communication step must be > 0 and finite, got %s", py_repr(h, (char[REPR_SIZE]){0}))
        : h <= ROUNDING_STEP ? MODEL_OK : c->type->do_step(c->type, c->model, t, h, &r); /* runtime.py's rule */
    status = settle(c, status, 0);
    if (status <= MODEL_WARNING) c->time = t + h;
    return status;
}

/* ---- FMU states ---- */

static const char *const NOT_OURS = "not an FMU state of this instance (or one already freed)";

/* The check of a host's `FMUstate *` argument: NULL (refused), the state itself where its address belongs, or an
   address holding neither NULL (when `null_ok`) nor one of this instance's states. NULL if the pointer may be
   used, else the reason. */
static const char *bad_state_address(const Instance *c, void **state, int null_ok) {
    if (!state) return "NULL state pointer";
    if (is_own_state(c, state)) return "given an FMU state where the address of one belongs";
    if (!*state) return null_ok ? NULL : "NULL state";
    return is_own_state(c, *state) ? NULL : NOT_OURS;
}

/* A new state, remembered as this instance's; NULL when out of memory. */
static SavedState *new_state(Instance *c) {
    if (c->n_states == c->states_size) {
        size_t size = c->states_size ? 2 * c->states_size : 4;
        SavedState **states = realloc(c->states, size * sizeof *states);
        if (!states) return NULL;
        c->states = states, c->states_size = size;
    }
    SavedState *state = calloc(1, sizeof *state);
    if (state) c->states[c->n_states++] = state;
    return state;
}

/* The model saved into `state` (its block copied for plain data, else by the model). */
static ModelStatus save_model(Instance *c, SavedState *state, const Reporter *r) {
    if (c->type->states) return c->type->states->save(c->type, c->model, &state->model, r);
    size_t size = c->type->size(c->type);
    if (!state->model && !(state->model = malloc(size))) return report(r, MODEL_ERROR, "out of memory");
    memcpy(state->model, c->model, size);
    return MODEL_OK;
}

int get_fmu_state(Instance *c, const char *function, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    const char *bad = bad_state_address(c, state, 1);
    if (bad) return refuse(c, function, bad);
    SavedState *saved = *state ? *state : new_state(c);
    if (!saved) return refuse(c, function, "out of memory");
    Reporter r = reporter(c, function);
    ModelStatus status = save_model(c, saved, &r);
    if (status > MODEL_WARNING && !*state) drop_state(c, saved); /* a new one that holds nothing */
    if (status > MODEL_WARNING) return settle(c, status, 0);
    saved->mode = c->mode, saved->time = c->time;
    *state = saved;
    return status;
}

int set_fmu_state(Instance *c, const char *function, void *state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state) return refuse(c, function, "NULL state");
    if (!is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    const SavedState *saved = state;
    ModelStatus status = MODEL_OK;
    Reporter r = reporter(c, function);
    if (c->type->states) status = settle(c, c->type->states->restore(c->type, c->model, saved->model, &r), 0);
    else memcpy(c->model, saved->model, c->type->size(c->type));
    if (status <= MODEL_WARNING) c->mode = saved->mode, c->time = saved->time;
    return status;
}

int free_fmu_state(Instance *c, const char *function, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    const char *bad = bad_state_address(c, state, 1);
    if (bad) return refuse(c, function, bad);
    if (*state) drop_state(c, *state);
    *state = NULL;
    return MODEL_OK;
}

/* A serialised state: this header, then the model's bytes (its block, or what the model serialises). */
typedef struct {
    char magic[4]; /* "CRF1" */
    int mode;
    double time;
} StateHeader;

/* The serialised state into *bytes (malloc'd) and *size; logged and NULL on failure. */
static ModelStatus serialized(Instance *c, const char *function, const SavedState *saved, unsigned char **bytes,
                              size_t *size) {
    StateHeader header = {{'C', 'R', 'F', '1'}, saved->mode, saved->time};
    unsigned char *body = NULL;
    size_t body_size = c->type->size(c->type);
    if (c->type->states) {
        Reporter r = reporter(c, function);
        ModelStatus status = c->type->states->serialize(c->type, c->model, saved->model, &body, &body_size, &r);
        if (status > MODEL_WARNING) return settle(c, status, 0);
    }
    *size = sizeof header + body_size;
    *bytes = malloc(*size);
    if (*bytes) {
        memcpy(*bytes, &header, sizeof header);
        memcpy(*bytes + sizeof header, body ? body : saved->model, body_size);
    }
    free(body);
    return *bytes ? MODEL_OK : refuse(c, function, "out of memory");
}

int serialized_size(Instance *c, const char *function, void *state, size_t *size) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!state || !size) return refuse(c, function, "NULL state or size");
    if (!is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    unsigned char *bytes;
    ModelStatus status = serialized(c, function, state, &bytes, size);
    if (status <= MODEL_WARNING) free(bytes);
    return status;
}

int serialize_fmu_state(Instance *c, const char *function, void *state, unsigned char out[], size_t size) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    if (!out) return refuse(c, function, "NULL buffer");
    if (!is_own_state(c, state)) return refuse(c, function, NOT_OURS);
    unsigned char *bytes;
    size_t needed;
    ModelStatus status = serialized(c, function, state, &bytes, &needed);
    if (status > MODEL_WARNING) return status;
    if (size < needed) status = refuse(c, function, "the buffer is too small");
    else memcpy(out, bytes, needed);
    free(bytes);
    return status;
}

int deserialize_fmu_state(Instance *c, const char *function, const unsigned char data[], size_t size, void **state) {
    if (!allowed(c, function, ANY_MODE)) return MODEL_ERROR;
    const char *bad = bad_state_address(c, state, 1);
    if (bad) return refuse(c, function, bad);
    StateHeader header;
    size_t body = size - sizeof header;
    if (!data || size < sizeof header || (memcpy(&header, data, sizeof header), memcmp(header.magic, "CRF1", 4)) ||
        !(header.mode & ANY_MODE) || (header.mode & (header.mode - 1)) != 0 ||
        (!c->type->states && body != c->type->size(c->type)))
        return refuse(c, function, "not a serialised state of this FMU (of this build)");
    SavedState *saved = *state ? *state : new_state(c);
    if (!saved) return refuse(c, function, "out of memory");
    ModelStatus status = MODEL_OK;
    if (c->type->states) {
        void *model = saved->model; /* overwritten only when the model has read the bytes */
        Reporter r = reporter(c, function);
        status = c->type->states->deserialize(c->type, c->model, data + sizeof header, body, &model, &r);
        if (status <= MODEL_WARNING) saved->model = model;
    } else if (!saved->model && !(saved->model = malloc(body))) {
        status = refuse(c, function, "out of memory");
    } else {
        memcpy(saved->model, data + sizeof header, body);
    }
    if (status > MODEL_WARNING) {
        if (!*state) drop_state(c, saved);
        return settle(c, status, 0);
    }
    saved->mode = header.mode, saved->time = header.time;
    *state = saved;
    return status;
}
