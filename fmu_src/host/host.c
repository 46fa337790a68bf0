/*
 * A C host for any native FMU alone (FMI 2.0 or 3.0) and for a plant and a controller exchanged as our master
 * does, for the tests and `crane-fmu bench --native` (not part of any FMU): compiled for Linux (dlopen) and,
 * with mingw-w64, for Windows (LoadLibrary) to run under Wine. No Python anywhere, and no model: what it reads
 * and sets are value references given on the command line (X: the first of six consecutive ones, a plant's
 * x, dx, theta1, dtheta1, theta2, dtheta2 or a controller's measured ones).
 *
 *   host run LIB GUID STEPS H X                         rows "t,the six Reals from X" after each step of H
 *   host cycles LIB GUID N X                            N instantiate/initialise/step/free cycles; RSS per 1000
 *   host after-failure LIB GUID STEPS H X VR=VALUE      a run refused (VR set to VALUE), then a good one: its last row
 *   host threads LIB GUID STEPS H X                     two instances in two threads vs one alone: "same" or "differ"
 *   host maps LIB GUID                                  the libraries loaded in this process that name python
 *   host pair LIB GUID CLIB CGUID STEPS H X U CX CU     a plant (LIB: its six states from X, its input U) and a
 *                                                       controller (CLIB: its six measured inputs from CX, its
 *                                                       output CU), exchanged by value references at each step as
 *                                                       our master does: rows "t,6 states,u"
 *   host pair-bench LIB GUID CLIB CGUID STEPS H X U CX CU  seconds per step of that loop, no recording, and
 *                                                       its CPU seconds per step
 *   host outputs LIB GUID STEPS H [VR=VALUE]... VR...    any FMI 2.0 FMU (e.g. a system as one FMU): Real
 *                                                       parameters set (and Strings: "VRs=TEXT", Enumerations:
 *                                                       "VRi=VALUE", as an Integer), then rows
 *                                                       "t,the Reals of VR..." at t = k H after k steps
 *   host outputs3 LIB TOKEN STEPS H [VR=VALUE]... VR... the same for any FMI 3.0 co-simulation FMU (TOKEN: its
 *                                                       instantiationToken): Float64 (and String) parameters set,
 *                                                       Float64s read
 *                                                       (its value references: FMI 2.0's plus one in ours)
 *   host me LIB GUID STEPS H NX NZ [VR=VALUE]... VR...   an FMI 2.0 Model Exchange FMU (NX continuous states, NZ
 *                                                       event indicators) integrated here: the classic RK4 at H,
 *                                                       an event where an indicator changes sign at a step's end
 *                                                       (not located within the step); rows as `outputs`' until
 *                                                       the FMU asks to terminate
 *   host me3 LIB TOKEN STEPS H NX NZ [VR=VALUE]... VR... the same for an FMI 3.0 Model Exchange FMU
 *   host cases PLAN                                     the cases of a system of FMI 2.0 FMUs (PLAN: a file written by
 *                                                       crane_fmu/bench_batch.py, its format at run_cases below) as the
 *                                                       batch path runs them, without recording: "CASES SECONDS CPU"
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#ifdef _WIN32
#include <windows.h>
#define OPEN(path) ((void *)LoadLibraryA(path))
#define SYMBOL(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#include <pthread.h>
#define OPEN(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(lib, name) dlsym(lib, name)
#endif

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2GetRealTYPE *get;
    fmi2SetRealTYPE *set;
    fmi2DoStepTYPE *step;
    fmi2SetStringTYPE *set_string;
    fmi2SetIntegerTYPE *set_integer;
    const char *guid;
    void *lib; /* the library, for the functions a mode needs beyond these */
} Api;

static int quiet;
static const char *instance_name = "plant";

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String format, ...) {
    (void)env, (void)name, (void)category;
    if (quiet) return;
    va_list args;
    va_start(args, format);
    fprintf(stderr, "[%d] ", status);
    vfprintf(stderr, format, args);
    fputc('\n', stderr);
    va_end(args);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static void *open_library(const char *library) {
    void *lib = OPEN(library);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", library);
        exit(3);
    }
    return lib;
}

static Api load(const char *library, const char *guid) {
    void *lib = open_library(library);
    Api api = {(fmi2InstantiateTYPE *)SYMBOL(lib, "fmi2Instantiate"),
               (fmi2FreeInstanceTYPE *)SYMBOL(lib, "fmi2FreeInstance"),
               (fmi2SetupExperimentTYPE *)SYMBOL(lib, "fmi2SetupExperiment"),
               (fmi2EnterInitializationModeTYPE *)SYMBOL(lib, "fmi2EnterInitializationMode"),
               (fmi2ExitInitializationModeTYPE *)SYMBOL(lib, "fmi2ExitInitializationMode"),
               (fmi2GetRealTYPE *)SYMBOL(lib, "fmi2GetReal"),
               (fmi2SetRealTYPE *)SYMBOL(lib, "fmi2SetReal"),
               (fmi2DoStepTYPE *)SYMBOL(lib, "fmi2DoStep"),
               (fmi2SetStringTYPE *)SYMBOL(lib, "fmi2SetString"),
               (fmi2SetIntegerTYPE *)SYMBOL(lib, "fmi2SetInteger"),
               guid,
               lib};
    if (!api.instantiate || !api.step) {
        fprintf(stderr, "missing FMI functions in %s\n", library);
        exit(3);
    }
    return api;
}

enum { MAX_VR = 64 };

/* The String settings ("VRs=TEXT") of the `outputs` and `outputs3` modes, set after the Reals. */
static struct {
    unsigned int vr[MAX_VR];
    const char *value[MAX_VR];
    size_t n;
} strings;

/* The Enumeration settings ("VRi=VALUE", an item's value) of the same modes, set after the Strings. */
static struct {
    unsigned int vr[MAX_VR];
    int value[MAX_VR];
    size_t n;
} integers;

/* An initialised instance with the given parameter settings (and `strings`), or NULL (the FMU logged why). */
static fmi2Component start(const Api *api, size_t n, const fmi2ValueReference vr[], const fmi2Real v[]) {
    fmi2Component c = api->instantiate(instance_name, fmi2CoSimulation, api->guid, "", &callbacks, fmi2False, fmi2False);
    if (!c) return NULL;
    if (api->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning || api->enter(c) > fmi2Warning ||
        (n && api->set(c, vr, n, v) > fmi2Warning) ||
        (strings.n && (!api->set_string || api->set_string(c, strings.vr, strings.n, strings.value) > fmi2Warning)) ||
        (integers.n &&
         (!api->set_integer || api->set_integer(c, integers.vr, integers.n, integers.value) > fmi2Warning)) ||
        api->exit_init(c) > fmi2Warning) {
        api->free_instance(c);
        return NULL;
    }
    return c;
}

/* `steps` steps of h; the six Reals from x after each step into rows (7 a row). */
static int run(const Api *api, fmi2Component c, fmi2ValueReference x, int steps, double h, double *rows) {
    const fmi2ValueReference states[6] = {x, x + 1, x + 2, x + 3, x + 4, x + 5};
    for (int k = 0; k <= steps; k++) {
        double t = k * h;
        rows[7 * k] = t;
        if (api->get(c, states, 6, rows + 7 * k + 1) > fmi2Warning) return 0;
        if (k == steps) break;
        if (api->step(c, t, h, fmi2True) > fmi2Warning) return 0;
    }
    return 1;
}

static void print_rows(const double *rows, int steps) {
    for (int k = 0; k <= steps; k++)
        for (int i = 0; i < 7; i++) printf(i < 6 ? "%.17g," : "%.17g\n", rows[7 * k + i]);
}

static double *rows_for(int steps) {
    double *rows = calloc((size_t)(steps + 1) * 7, sizeof *rows);
    if (!rows) exit(5);
    return rows;
}

static double seconds(void) {
#ifdef _WIN32
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
#else
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#endif
}

static long rss_kb(void) {
#ifdef _WIN32
    return -1;
#else
    long pages = -1, resident = -1;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f && fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = -1;
    if (f) fclose(f);
    return resident * 4;
#endif
}

#ifndef _WIN32
typedef struct {
    const Api *api;
    fmi2ValueReference x;
    int steps;
    double h;
    double *rows;
    int ok;
} Job;

static void *run_job(void *arg) {
    Job *job = arg;
    fmi2Component c = start(job->api, 0, NULL, NULL);
    job->ok = c && run(job->api, c, job->x, job->steps, job->h, job->rows);
    if (c) job->api->free_instance(c);
    return NULL;
}
#endif

/* The value references of a closed loop: the plant's states (from x) and input u, the controller's measured
   states (from cx) and output cu. */
typedef struct {
    fmi2ValueReference x, u, cx, cu;
} Loop;

/* A closed loop on two FMUs, Gauss-Seidel as our master: the plant's states into the controller, its u into
   the plant, then both step. Rows "t,6 states,u" when `rows` is given; seconds per step returned (and the CPU
   seconds per step in *cpu). */
static double run_pair(const Api *plant, const Api *law, Loop vr, int steps, double h, FILE *rows, double *cpu) {
    const fmi2ValueReference states[6] = {vr.x, vr.x + 1, vr.x + 2, vr.x + 3, vr.x + 4, vr.x + 5}, u_vr = vr.u;
    const fmi2ValueReference cx = vr.cx, out_vr = vr.cu;
    const fmi2ValueReference measured[6] = {cx, cx + 1, cx + 2, cx + 3, cx + 4, cx + 5};
    fmi2Component p = start(plant, 0, NULL, NULL);
    instance_name = "controller";
    fmi2Component c = start(law, 0, NULL, NULL);
    if (!p || !c) exit(6);
    double y[6], u, t0 = seconds();
    clock_t c0 = clock();
    for (int k = 0; k <= steps; k++) {
        if (plant->get(p, states, 6, y) > fmi2Warning || law->set(c, measured, 6, y) > fmi2Warning ||
            law->get(c, &out_vr, 1, &u) > fmi2Warning || plant->set(p, &u_vr, 1, &u) > fmi2Warning)
            exit(6);
        if (rows) fprintf(rows, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k * h, y[0], y[1], y[2], y[3], y[4],
                          y[5], u);
        if (k == steps) break;
        if (plant->step(p, k * h, h, fmi2True) > fmi2Warning || law->step(c, k * h, h, fmi2True) > fmi2Warning) exit(6);
    }
    double per_step = (seconds() - t0) / steps;
    *cpu = (double)(clock() - c0) / CLOCKS_PER_SEC / steps;
    plant->free_instance(p);
    law->free_instance(c);
    return per_step;
}

/* The "VR=VALUE" settings of args (into set_vr, set_v), the "VRs=TEXT" ones (into `strings`) and the other args'
   VRs to read (into get_vr). */
static int parse_vrs(int n_args, char **args, unsigned int set_vr[], double set_v[], size_t *n_set,
                     unsigned int get_vr[], size_t *n_get) {
    *n_set = *n_get = strings.n = integers.n = 0;
    for (int i = 0; i < n_args; i++) {
        char *end;
        unsigned int vr = (unsigned int)strtoul(args[i], &end, 10);
        if (end[0] == 's' && end[1] == '=') {
            if (strings.n == MAX_VR) return 0;
            strings.vr[strings.n] = vr, strings.value[strings.n++] = end + 2;
            continue;
        }
        if (end[0] == 'i' && end[1] == '=') {
            if (integers.n == MAX_VR) return 0;
            integers.vr[integers.n] = vr, integers.value[integers.n++] = atoi(end + 2);
            continue;
        }
        const char *eq = strchr(args[i], '=');
        if ((eq ? *n_set : *n_get) == MAX_VR) return 0;
        if (eq) set_vr[*n_set] = vr, set_v[(*n_set)++] = strtod(eq + 1, NULL);
        else get_vr[(*n_get)++] = vr;
    }
    return 1;
}

/* Any FMU alone: the Real settings "VR=VALUE" of args, then rows "t,values" of the other args' VRs at each step. */
static int print_outputs(const Api *api, int steps, double h, int n_args, char **args) {
    fmi2ValueReference set_vr[MAX_VR], get_vr[MAX_VR];
    double set_v[MAX_VR], y[MAX_VR];
    size_t n_set, n_get;
    if (!parse_vrs(n_args, args, set_vr, set_v, &n_set, get_vr, &n_get)) return 0;
    fmi2Component c = start(api, n_set, set_vr, set_v);
    if (!c) return 0;
    for (int k = 0; k <= steps; k++) {
        if (api->get(c, get_vr, n_get, y) > fmi2Warning) return 0;
        printf("%.17g", k * h);
        for (size_t i = 0; i < n_get; i++) printf(",%.17g", y[i]);
        putchar('\n');
        if (k < steps && api->step(c, k * h, h, fmi2True) > fmi2Warning) return 0;
    }
    api->free_instance(c);
    return 1;
}

/* ---- FMI 3.0: the `outputs3` mode ---------------------------------------------------------------------------- */

/* The Enumeration settings of `integers` on an FMI 3.0 instance (as Int64s); 1 when set (or none). */
static int set_int64s(fmi3SetInt64TYPE *set_int64, fmi3Instance c) {
    fmi3Int64 values[MAX_VR];
    for (size_t i = 0; i < integers.n; i++) values[i] = integers.value[i];
    return !integers.n || (set_int64 && set_int64(c, integers.vr, integers.n, values, integers.n) <= fmi3Warning);
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env, (void)category;
    if (!quiet) fprintf(stderr, "[%d] %s\n", status, message);
}

/* print_outputs() for an FMI 3.0 co-simulation FMU: Float64 settings in initialization mode, then rows of Float64s. */
static int print_outputs3(const char *library, const char *token, int steps, double h, int n_args, char **args) {
    void *lib = open_library(library);
    fmi3InstantiateCoSimulationTYPE *instantiate =
        (fmi3InstantiateCoSimulationTYPE *)SYMBOL(lib, "fmi3InstantiateCoSimulation");
    fmi3FreeInstanceTYPE *free_instance = (fmi3FreeInstanceTYPE *)SYMBOL(lib, "fmi3FreeInstance");
    fmi3EnterInitializationModeTYPE *enter =
        (fmi3EnterInitializationModeTYPE *)SYMBOL(lib, "fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE *exit_init =
        (fmi3ExitInitializationModeTYPE *)SYMBOL(lib, "fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE *set = (fmi3SetFloat64TYPE *)SYMBOL(lib, "fmi3SetFloat64");
    fmi3GetFloat64TYPE *get = (fmi3GetFloat64TYPE *)SYMBOL(lib, "fmi3GetFloat64");
    fmi3DoStepTYPE *step = (fmi3DoStepTYPE *)SYMBOL(lib, "fmi3DoStep");
    fmi3SetStringTYPE *set_string = (fmi3SetStringTYPE *)SYMBOL(lib, "fmi3SetString");
    fmi3SetInt64TYPE *set_int64 = (fmi3SetInt64TYPE *)SYMBOL(lib, "fmi3SetInt64");
    if (!instantiate || !free_instance || !enter || !exit_init || !set || !get || !step || !set_string) {
        fprintf(stderr, "missing FMI 3.0 functions in %s\n", library);
        exit(3);
    }
    fmi3ValueReference set_vr[MAX_VR], get_vr[MAX_VR];
    double set_v[MAX_VR], y[MAX_VR];
    size_t n_set, n_get;
    if (!parse_vrs(n_args, args, set_vr, set_v, &n_set, get_vr, &n_get)) return 0;
    fmi3Instance c = instantiate(instance_name, token, "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                 logger3, NULL);
    if (!c) return 0;
    int ok = enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) <= fmi3Warning &&
             (!n_set || set(c, set_vr, n_set, set_v, n_set) <= fmi3Warning) &&
             (!strings.n || set_string(c, strings.vr, strings.n, strings.value, strings.n) <= fmi3Warning) &&
             set_int64s(set_int64, c) && exit_init(c) <= fmi3Warning;
    for (int k = 0; ok && k <= steps; k++) {
        fmi3Boolean event, terminate, early;
        fmi3Float64 last;
        if (get(c, get_vr, n_get, y, n_get) > fmi3Warning) ok = 0;
        else {
            printf("%.17g", k * h);
            for (size_t i = 0; i < n_get; i++) printf(",%.17g", y[i]);
            putchar('\n');
            if (k < steps && (step(c, k * h, h, fmi3True, &event, &terminate, &early, &last) > fmi3Warning || terminate))
                ok = 0;
        }
    }
    free_instance(c);
    return ok;
}

/* ---- Model Exchange: the `me` and `me3` modes ------------------------------------------------------------------ */

/* A Model Exchange instance of either FMI version as integrate() drives it (one per process): each call returns 1
   on success (OK or warning). */
typedef struct {
    size_t nx, nz;
    int (*set_time)(double t);
    int (*set_states)(const double x[]);
    int (*get_states)(double x[]);
    int (*derivatives)(double dx[]);
    int (*indicators)(double z[]);
    int (*enter_event_mode)(void);
    int (*update)(int *again, int *terminate); /* one event update */
    int (*enter_continuous)(void);
    int (*completed)(int *event, int *terminate);
    int (*get)(const unsigned vr[], size_t n, double v[]);
} Me;

/* The derivatives dx at (t, x); 0 if the FMU refused. */
static int slope(const Me *me, double t, const double x[], double dx[]) {
    return me->set_time(t) && me->set_states(x) && me->derivatives(dx);
}

/* Event iteration until the FMU needs no more; then continuous-time mode, the states and indicators read again.
   0 if the FMU refused; *terminate: the FMU asks to end the simulation. */
static int event_iteration(const Me *me, double x[], double z[], int *terminate) {
    int again = 1;
    *terminate = 0;
    while (again && !*terminate)
        if (!me->update(&again, terminate)) return 0;
    return *terminate || (me->enter_continuous() && me->get_states(x) && me->indicators(z));
}

enum { MAX_STATES = 64 };

/* From event mode after initialisation: rows "t,values of get_vr" at t = k h, the classic RK4 between them. */
static int integrate(const Me *me, int steps, double h, size_t n_get, const unsigned get_vr[]) {
    double x[MAX_STATES], z[MAX_STATES], z_new[MAX_STATES], k[4][MAX_STATES], trial[MAX_STATES], y[MAX_VR];
    size_t n = me->nx;
    int terminate = 0;
    if (!event_iteration(me, x, z, &terminate)) return 0;
    for (int step = 0; step <= steps; step++) {
        double t = step * h;
        if (!me->get(get_vr, n_get, y)) return 0;
        printf("%.17g", t);
        for (size_t i = 0; i < n_get; i++) printf(",%.17g", y[i]);
        putchar('\n');
        if (terminate || step == steps) break;
        static const double at[4] = {0.0, 0.5, 0.5, 1.0};
        for (int s = 0; s < 4; s++) {
            for (size_t i = 0; i < n; i++) trial[i] = s ? x[i] + at[s] * h * k[s - 1][i] : x[i];
            if (!slope(me, s == 3 ? (step + 1) * h : t + at[s] * h, trial, k[s])) return 0;
        }
        for (size_t i = 0; i < n; i++) x[i] += h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
        int enter = 0;
        if (!me->set_time((step + 1) * h) || !me->set_states(x) || !me->completed(&enter, &terminate) ||
            !me->indicators(z_new))
            return 0;
        int crossed = enter;
        for (size_t i = 0; i < me->nz; i++) crossed |= (z[i] > 0) != (z_new[i] > 0);
        memcpy(z, z_new, me->nz * sizeof *z);
        if (crossed && !terminate && (!me->enter_event_mode() || !event_iteration(me, x, z, &terminate))) return 0;
    }
    return 1;
}

/* FMI 2.0: the library's functions and the one instance */
static struct {
    fmi2Component c;
    size_t nx, nz;
    fmi2SetTimeTYPE *set_time;
    fmi2SetContinuousStatesTYPE *set_states;
    fmi2GetContinuousStatesTYPE *get_states;
    fmi2GetDerivativesTYPE *derivatives;
    fmi2GetEventIndicatorsTYPE *indicators;
    fmi2EnterEventModeTYPE *enter_event_mode;
    fmi2NewDiscreteStatesTYPE *update;
    fmi2EnterContinuousTimeModeTYPE *enter_continuous;
    fmi2CompletedIntegratorStepTYPE *completed;
    fmi2GetRealTYPE *get;
} m2;
static int set_time2(double t) { return m2.set_time(m2.c, t) <= fmi2Warning; }
static int set_states2(const double x[]) { return m2.set_states(m2.c, x, m2.nx) <= fmi2Warning; }
static int get_states2(double x[]) { return m2.get_states(m2.c, x, m2.nx) <= fmi2Warning; }
static int derivatives2(double dx[]) { return m2.derivatives(m2.c, dx, m2.nx) <= fmi2Warning; }
static int indicators2(double z[]) { return m2.indicators(m2.c, z, m2.nz) <= fmi2Warning; }
static int enter_event_mode2(void) { return m2.enter_event_mode(m2.c) <= fmi2Warning; }
static int update2(int *again, int *terminate) {
    fmi2EventInfo info;
    if (m2.update(m2.c, &info) > fmi2Warning) return 0;
    *again = info.newDiscreteStatesNeeded, *terminate = info.terminateSimulation;
    return 1;
}
static int enter_continuous2(void) { return m2.enter_continuous(m2.c) <= fmi2Warning; }
static int completed2(int *event, int *terminate) {
    fmi2Boolean e = fmi2False, t = fmi2False;
    if (m2.completed(m2.c, fmi2True, &e, &t) > fmi2Warning) return 0;
    *event = e, *terminate = t;
    return 1;
}
static int get2(const unsigned vr[], size_t n, double v[]) { return m2.get(m2.c, vr, n, v) <= fmi2Warning; }

static int mode_me(const Api *api, const char *mode, int n, char **a) { /* STEPS H NX NZ [VR=VALUE]... VR... */
    (void)mode;
    if (n < 4) return 2;
    void *lib = api->lib;
    m2.set_time = (fmi2SetTimeTYPE *)SYMBOL(lib, "fmi2SetTime");
    m2.set_states = (fmi2SetContinuousStatesTYPE *)SYMBOL(lib, "fmi2SetContinuousStates");
    m2.get_states = (fmi2GetContinuousStatesTYPE *)SYMBOL(lib, "fmi2GetContinuousStates");
    m2.derivatives = (fmi2GetDerivativesTYPE *)SYMBOL(lib, "fmi2GetDerivatives");
    m2.indicators = (fmi2GetEventIndicatorsTYPE *)SYMBOL(lib, "fmi2GetEventIndicators");
    m2.enter_event_mode = (fmi2EnterEventModeTYPE *)SYMBOL(lib, "fmi2EnterEventMode");
    m2.update = (fmi2NewDiscreteStatesTYPE *)SYMBOL(lib, "fmi2NewDiscreteStates");
    m2.enter_continuous = (fmi2EnterContinuousTimeModeTYPE *)SYMBOL(lib, "fmi2EnterContinuousTimeMode");
    m2.completed = (fmi2CompletedIntegratorStepTYPE *)SYMBOL(lib, "fmi2CompletedIntegratorStep");
    m2.get = api->get;
    m2.nx = (size_t)atoi(a[2]), m2.nz = (size_t)atoi(a[3]);
    if (!m2.set_time || !m2.completed || m2.nx > MAX_STATES || m2.nz > MAX_STATES) return 3;
    Me me = {m2.nx, m2.nz, set_time2, set_states2, get_states2, derivatives2, indicators2, enter_event_mode2,
             update2, enter_continuous2, completed2, get2};
    fmi2ValueReference set_vr[MAX_VR], get_vr[MAX_VR];
    double set_v[MAX_VR];
    size_t n_set, n_get;
    if (!parse_vrs(n - 4, a + 4, set_vr, set_v, &n_set, get_vr, &n_get)) return 2;
    m2.c = api->instantiate(instance_name, fmi2ModelExchange, api->guid, "", &callbacks, fmi2False, fmi2False);
    if (!m2.c || api->setup(m2.c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning ||
        api->enter(m2.c) > fmi2Warning || (n_set && api->set(m2.c, set_vr, n_set, set_v) > fmi2Warning) ||
        api->exit_init(m2.c) > fmi2Warning)
        return 6;
    int ok = integrate(&me, atoi(a[0]), atof(a[1]), n_get, get_vr);
    api->free_instance(m2.c);
    return ok ? 0 : 6;
}

/* FMI 3.0: the same */
static struct {
    fmi3Instance c;
    size_t nx, nz;
    fmi3SetTimeTYPE *set_time;
    fmi3SetContinuousStatesTYPE *set_states;
    fmi3GetContinuousStatesTYPE *get_states;
    fmi3GetContinuousStateDerivativesTYPE *derivatives;
    fmi3GetEventIndicatorsTYPE *indicators;
    fmi3EnterEventModeTYPE *enter_event_mode;
    fmi3UpdateDiscreteStatesTYPE *update;
    fmi3EnterContinuousTimeModeTYPE *enter_continuous;
    fmi3CompletedIntegratorStepTYPE *completed;
    fmi3GetFloat64TYPE *get;
} m3;
static int set_time3(double t) { return m3.set_time(m3.c, t) <= fmi3Warning; }
static int set_states3(const double x[]) { return m3.set_states(m3.c, x, m3.nx) <= fmi3Warning; }
static int get_states3(double x[]) { return m3.get_states(m3.c, x, m3.nx) <= fmi3Warning; }
static int derivatives3(double dx[]) { return m3.derivatives(m3.c, dx, m3.nx) <= fmi3Warning; }
static int indicators3(double z[]) { return m3.indicators(m3.c, z, m3.nz) <= fmi3Warning; }
static int enter_event_mode3(void) { return m3.enter_event_mode(m3.c) <= fmi3Warning; }
static int update3(int *again, int *terminate) {
    fmi3Boolean needed, end, nominals, values, defined;
    fmi3Float64 next;
    if (m3.update(m3.c, &needed, &end, &nominals, &values, &defined, &next) > fmi3Warning) return 0;
    *again = needed, *terminate = end;
    return 1;
}
static int enter_continuous3(void) { return m3.enter_continuous(m3.c) <= fmi3Warning; }
static int completed3(int *event, int *terminate) {
    fmi3Boolean e = fmi3False, t = fmi3False;
    if (m3.completed(m3.c, fmi3True, &e, &t) > fmi3Warning) return 0;
    *event = e, *terminate = t;
    return 1;
}
static int get3(const unsigned vr[], size_t n, double v[]) { return m3.get(m3.c, vr, n, v, n) <= fmi3Warning; }

/* me3 LIB TOKEN STEPS H NX NZ [VR=VALUE]... VR...: `me` for an FMI 3.0 FMU (its value references) */
static int me3(const char *library, const char *token, int n, char **a) {
    if (n < 4) return 2;
    void *lib = open_library(library);
    fmi3InstantiateModelExchangeTYPE *instantiate =
        (fmi3InstantiateModelExchangeTYPE *)SYMBOL(lib, "fmi3InstantiateModelExchange");
    fmi3FreeInstanceTYPE *free_instance = (fmi3FreeInstanceTYPE *)SYMBOL(lib, "fmi3FreeInstance");
    fmi3EnterInitializationModeTYPE *enter =
        (fmi3EnterInitializationModeTYPE *)SYMBOL(lib, "fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE *exit_init =
        (fmi3ExitInitializationModeTYPE *)SYMBOL(lib, "fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE *set = (fmi3SetFloat64TYPE *)SYMBOL(lib, "fmi3SetFloat64");
    m3.set_time = (fmi3SetTimeTYPE *)SYMBOL(lib, "fmi3SetTime");
    m3.set_states = (fmi3SetContinuousStatesTYPE *)SYMBOL(lib, "fmi3SetContinuousStates");
    m3.get_states = (fmi3GetContinuousStatesTYPE *)SYMBOL(lib, "fmi3GetContinuousStates");
    m3.derivatives = (fmi3GetContinuousStateDerivativesTYPE *)SYMBOL(lib, "fmi3GetContinuousStateDerivatives");
    m3.indicators = (fmi3GetEventIndicatorsTYPE *)SYMBOL(lib, "fmi3GetEventIndicators");
    m3.enter_event_mode = (fmi3EnterEventModeTYPE *)SYMBOL(lib, "fmi3EnterEventMode");
    m3.update = (fmi3UpdateDiscreteStatesTYPE *)SYMBOL(lib, "fmi3UpdateDiscreteStates");
    m3.enter_continuous = (fmi3EnterContinuousTimeModeTYPE *)SYMBOL(lib, "fmi3EnterContinuousTimeMode");
    m3.completed = (fmi3CompletedIntegratorStepTYPE *)SYMBOL(lib, "fmi3CompletedIntegratorStep");
    m3.get = (fmi3GetFloat64TYPE *)SYMBOL(lib, "fmi3GetFloat64");
    m3.nx = (size_t)atoi(a[2]), m3.nz = (size_t)atoi(a[3]);
    if (!instantiate || !set || !m3.set_time || !m3.completed || m3.nx > MAX_STATES || m3.nz > MAX_STATES) return 3;
    Me me = {m3.nx, m3.nz, set_time3, set_states3, get_states3, derivatives3, indicators3, enter_event_mode3,
             update3, enter_continuous3, completed3, get3};
    fmi3ValueReference set_vr[MAX_VR], get_vr[MAX_VR];
    double set_v[MAX_VR];
    size_t n_set, n_get;
    if (!parse_vrs(n - 4, a + 4, set_vr, set_v, &n_set, get_vr, &n_get)) return 2;
    m3.c = instantiate(instance_name, token, "", fmi3False, fmi3False, NULL, logger3);
    if (!m3.c || enter(m3.c, fmi3False, 0.0, 0.0, fmi3False, 0.0) > fmi3Warning ||
        (n_set && set(m3.c, set_vr, n_set, set_v, n_set) > fmi3Warning) || exit_init(m3.c) > fmi3Warning)
        return 6;
    int ok = integrate(&me, atoi(a[0]), atof(a[1]), n_get, get_vr);
    free_instance(m3.c);
    return ok ? 0 : 6;
}

/* ---- the modes: each gets its arguments after LIB GUID and returns the exit status ---------------------------- */

#define VR(text) ((fmi2ValueReference)atoi(text))

static int mode_outputs(const Api *api, const char *mode, int n, char **a) { /* STEPS H [VR=VALUE]... VR... */
    (void)mode;
    return n >= 2 && print_outputs(api, atoi(a[0]), atof(a[1]), n - 2, a + 2) ? 0 : 6;
}

static int mode_pair(const Api *api, const char *mode, int n, char **a) { /* CLIB CGUID STEPS H X U CX CU */
    if (n != 8) return 2;
    Api law = load(a[0], a[1]);
    int bench = !strcmp(mode, "pair-bench");
    double cpu, per_step = run_pair(api, &law, (Loop){VR(a[4]), VR(a[5]), VR(a[6]), VR(a[7])}, atoi(a[2]),
                                    atof(a[3]), bench ? NULL : stdout, &cpu);
    if (bench) printf("%.9g %.9g\n", per_step, cpu);
    return 0;
}

static int mode_run(const Api *api, const char *mode, int n, char **a) { /* STEPS H X */
    (void)mode;
    if (n != 3) return 2;
    int steps = atoi(a[0]);
    double *rows = rows_for(steps);
    fmi2Component c = start(api, 0, NULL, NULL);
    if (!c || !run(api, c, VR(a[2]), steps, atof(a[1]), rows)) return 6;
    api->free_instance(c);
    print_rows(rows, steps);
    return 0;
}

static int mode_cycles(const Api *api, const char *mode, int n, char **a) { /* N X */
    (void)mode;
    if (n != 2) return 2;
    quiet = 1;
    double rows[7 * 11];
    for (int i = 1; i <= atoi(a[0]); i++) {
        fmi2Component c = start(api, 0, NULL, NULL);
        if (!c || !run(api, c, VR(a[1]), 10, 1e-3, rows)) return 6;
        api->free_instance(c);
        if (i % 1000 == 0) printf("%d,%ld\n", i, rss_kb());
    }
    return 0;
}

static int mode_after_failure(const Api *api, const char *mode, int n, char **a) { /* STEPS H X VR=VALUE */
    (void)mode;
    fmi2ValueReference bad_vr;
    double bad;
    size_t n_bad, n_get;
    if (n != 4 || !parse_vrs(1, a + 3, &bad_vr, &bad, &n_bad, &bad_vr, &n_get) || n_bad != 1) return 2;
    int steps = atoi(a[0]);
    double *rows = rows_for(steps);
    if (start(api, 1, &bad_vr, &bad) != NULL) return 8; /* must be refused */
    fmi2Component c = start(api, 0, NULL, NULL);
    if (!c || !run(api, c, VR(a[2]), steps, atof(a[1]), rows)) return 6;
    api->free_instance(c);
    print_rows(rows + 7 * steps, 0);
    return 0;
}

#ifndef _WIN32
static int mode_threads(const Api *api, const char *mode, int n, char **a) { /* STEPS H X */
    (void)mode;
    if (n != 3) return 2;
    int steps = atoi(a[0]);
    double h = atof(a[1]);
    Job alone = {api, VR(a[2]), steps, h, rows_for(steps), 0}, jobs[2];
    run_job(&alone);
    pthread_t threads[2];
    for (int i = 0; i < 2; i++) {
        jobs[i] = (Job){api, VR(a[2]), steps, h, rows_for(steps), 0};
        if (pthread_create(&threads[i], NULL, run_job, &jobs[i])) return 9;
    }
    for (int i = 0; i < 2; i++) pthread_join(threads[i], NULL);
    size_t size = (size_t)(steps + 1) * 7 * sizeof(double);
    int same = alone.ok && jobs[0].ok && jobs[1].ok && !memcmp(alone.rows, jobs[0].rows, size) &&
               !memcmp(alone.rows, jobs[1].rows, size);
    printf(same ? "same\n" : "differ\n");
    return 0;
}

static int mode_maps(const Api *api, const char *mode, int n, char **a) {
    (void)mode, (void)n, (void)a;
    fmi2Component c = start(api, 0, NULL, NULL);
    if (!c) return 6;
    FILE *f = fopen("/proc/self/maps", "r");
    char line[4096];
    while (f && fgets(line, sizeof line, f))
        if (strstr(line, "python")) fputs(line, stdout);
    if (f) fclose(f);
    api->free_instance(c);
    return 0;
}
#endif

/*
 * The cases of a system as our master's batch path runs them (crane_fmu/cosim/reused.py), with nothing recorded: the
 * instances made once, then for each case reset (not the first), the experiment set up, the case's parameters set,
 * initialisation with the exchange, the steps (exchange, then every instance steps), the last exchange, terminate.
 * PLAN, whitespace-separated:
 *   N, then N times LIB GUID NAME                     the instances
 *   B                                                 the outputs' buffer: B doubles
 *   R, then R times I K VR*K SLOT                     the reads: K outputs of instance I into the buffer from SLOT
 *   W, then W times I K VR*K SLOT*K                   the writes: K inputs of instance I from the buffer's SLOTs
 *   E, then E times r|w INDEX                         the exchange: the reads and writes in order
 *   S, then S times I                                 the steps' order
 *   STEPS H STOP                                      t = k H for k < STEPS, then STOP
 *   C, then C times (N times: NR VR VALUE..., NS VR TEXT...)   the cases: each instance's parameters
 * Prints the cases run, the seconds they took (from the first instantiation to the last terminate) and the CPU
 * seconds.
 */
enum { MAX_INSTANCES = 16, MAX_CALLS = 64, MAX_SETTINGS = 64 };
typedef struct {
    int instance, k, slot[MAX_VR];
    fmi2ValueReference vr[MAX_VR];
    double values[MAX_VR];
} Call;

static int read_call(FILE *f, Call *c, int slots_each) {
    if (fscanf(f, "%d %d", &c->instance, &c->k) != 2 || c->instance < 0 || c->instance >= MAX_INSTANCES || c->k < 0 ||
        c->k > MAX_VR)
        return 0;
    for (int i = 0; i < c->k; i++)
        if (fscanf(f, "%u", &c->vr[i]) != 1) return 0;
    for (int i = 0; i < (slots_each ? c->k : 1); i++)
        if (fscanf(f, "%d", &c->slot[i]) != 1) return 0;
    return 1;
}

/* The exchange: the reads into the buffer and the writes from it, in order; 0 when a call fails. */
static int exchange(const Api api[], fmi2Component c[], double buffer[], const char kind[], const int index[], int n,
                    const Call reads[], Call writes[]) {
    for (int e = 0; e < n; e++) {
        if (kind[e] == 'r') {
            const Call *call = &reads[index[e]];
            if (api[call->instance].get(c[call->instance], call->vr, call->k, buffer + call->slot[0]) > fmi2Warning)
                return 0;
        } else {
            Call *call = &writes[index[e]];
            for (int j = 0; j < call->k; j++) call->values[j] = buffer[call->slot[j]];
            if (api[call->instance].set(c[call->instance], call->vr, call->k, call->values) > fmi2Warning) return 0;
        }
    }
    return 1;
}

static int run_cases(const char *plan_file) {
    FILE *f = fopen(plan_file, "r");
    static char libs[MAX_INSTANCES][1024], guids[MAX_INSTANCES][128], names[MAX_INSTANCES][128];
    static char texts[MAX_INSTANCES][MAX_SETTINGS][128];
    static Call reads[MAX_CALLS], writes[MAX_CALLS];
    Api api[MAX_INSTANCES];
    fmi2Component c[MAX_INSTANCES] = {0};
    fmi2ResetTYPE *reset[MAX_INSTANCES];
    fmi2TerminateTYPE *end[MAX_INSTANCES];
    char kind[MAX_CALLS];
    int n, b, n_reads, n_writes, n_exchange, n_steps, steps, cases, index[MAX_CALLS], order[MAX_INSTANCES];
    double h, stop;
    if (!f || fscanf(f, "%d", &n) != 1 || n < 1 || n > MAX_INSTANCES) return 2;
    for (int i = 0; i < n; i++) {
        if (fscanf(f, "%1023s %127s %127s", libs[i], guids[i], names[i]) != 3) return 2;
        api[i] = load(libs[i], guids[i]);
        reset[i] = (fmi2ResetTYPE *)SYMBOL(api[i].lib, "fmi2Reset");
        end[i] = (fmi2TerminateTYPE *)SYMBOL(api[i].lib, "fmi2Terminate");
    }
    if (fscanf(f, "%d", &b) != 1 || b < 1 || fscanf(f, "%d", &n_reads) != 1 || n_reads > MAX_CALLS) return 2;
    double *buffer = calloc((size_t)b, sizeof *buffer);
    for (int i = 0; i < n_reads; i++)
        if (!read_call(f, &reads[i], 0)) return 2;
    if (fscanf(f, "%d", &n_writes) != 1 || n_writes > MAX_CALLS) return 2;
    for (int i = 0; i < n_writes; i++)
        if (!read_call(f, &writes[i], 1)) return 2;
    if (fscanf(f, "%d", &n_exchange) != 1 || n_exchange > MAX_CALLS) return 2;
    for (int i = 0; i < n_exchange; i++)
        if (fscanf(f, " %c %d", &kind[i], &index[i]) != 2) return 2;
    if (fscanf(f, "%d", &n_steps) != 1 || n_steps > MAX_INSTANCES) return 2;
    for (int i = 0; i < n_steps; i++)
        if (fscanf(f, "%d", &order[i]) != 1) return 2;
    if (fscanf(f, "%d %lf %lf %d", &steps, &h, &stop, &cases) != 4 || !buffer) return 2;
    quiet = 1;
    double t0 = seconds();
    clock_t c0 = clock();
    for (int done = 0; done < cases; done++) {
        for (int i = 0; i < n; i++) {
            size_t nr, ns;
            Call real = {0};
            const char *text[MAX_SETTINGS];
            fmi2ValueReference string_vr[MAX_SETTINGS];
            if (fscanf(f, "%zu", &nr) != 1 || nr > MAX_VR) return 2;
            for (size_t j = 0; j < nr; j++)
                if (fscanf(f, "%u %lf", &real.vr[j], &real.values[j]) != 2) return 2;
            if (fscanf(f, "%zu", &ns) != 1 || ns > MAX_SETTINGS) return 2;
            for (size_t j = 0; j < ns; j++) {
                if (fscanf(f, "%u %127s", &string_vr[j], texts[i][j]) != 2) return 2;
                text[j] = texts[i][j];
            }
            instance_name = names[i];
            if (!c[i]) c[i] = api[i].instantiate(names[i], fmi2CoSimulation, guids[i], "", &callbacks, fmi2False, fmi2False);
            else if (reset[i](c[i]) > fmi2Warning) return 6;
            if (!c[i] || api[i].setup(c[i], fmi2False, 0.0, 0.0, fmi2True, stop) > fmi2Warning ||
                (nr && api[i].set(c[i], real.vr, nr, real.values) > fmi2Warning) ||
                (ns && api[i].set_string(c[i], string_vr, ns, text) > fmi2Warning) || api[i].enter(c[i]) > fmi2Warning)
                return 6;
        }
        if (!exchange(api, c, buffer, kind, index, n_exchange, reads, writes)) return 6; /* the initial exchange */
        for (int i = 0; i < n; i++)
            if (api[i].exit_init(c[i]) > fmi2Warning) return 6;
        for (long k = 0; k <= steps; k++) {
            if (!exchange(api, c, buffer, kind, index, n_exchange, reads, writes)) return 6;
            if (k == steps) break;
            for (int i = 0; i < n_steps; i++)
                if (api[order[i]].step(c[order[i]], k * h, h, fmi2True) > fmi2Warning) return 6;
        }
        for (int i = 0; i < n; i++)
            if (end[i](c[i]) > fmi2Warning) return 6;
    }
    printf("%d %.9g %.9g\n", cases, seconds() - t0, (double)(clock() - c0) / CLOCKS_PER_SEC);
    fclose(f);
    return 0;
}

static const struct {
    const char *name;
    int (*run)(const Api *api, const char *mode, int n, char **args);
} MODES[] = {{"outputs", mode_outputs}, {"pair", mode_pair}, {"pair-bench", mode_pair}, {"run", mode_run},
             {"cycles", mode_cycles}, {"after-failure", mode_after_failure}, {"me", mode_me},
#ifndef _WIN32
             {"threads", mode_threads}, {"maps", mode_maps},
#endif
};

int main(int argc, char **argv) {
    if (argc == 3 && !strcmp(argv[1], "cases")) return run_cases(argv[2]);
    if (argc < 4) return 2;
    const char *mode = argv[1];
    if (!strcmp(mode, "outputs3"))
        return argc >= 6 && print_outputs3(argv[2], argv[3], atoi(argv[4]), atof(argv[5]), argc - 6, argv + 6) ? 0 : 6;
    if (!strcmp(mode, "me3")) return me3(argv[2], argv[3], argc - 4, argv + 4);
    for (size_t i = 0; i < sizeof MODES / sizeof *MODES; i++)
        if (!strcmp(mode, MODES[i].name)) {
            Api api = load(argv[2], argv[3]);
            return MODES[i].run(&api, mode, argc - 4, argv + 4);
        }
    return 2;
}
