"""Random FMI call sequences from a C host, FMI 2.0 and 3.0, each call with the one status it must get.

The driver (seeded xorshift) picks calls at random, in any state, and keeps a shadow of the state
machine (FMI 2.0 section 4.2.4, FMI 3.0 section 4.2) to classify each call before making it:

- valid: allowed in the state, with good values: OK;
- wrong_state: not allowed in the state: error with a message, the state unchanged;
- bad_value: allowed, with a value the FMU refuses (a non-finite input, a step that is not > 0 and
  finite or needs more than 10^7 RK4 sub-steps, a NaN parameter at the end of initialisation or when
  a calculated variable is got before that, garbage as a serialised state): error with a message;
- long_step: a step of 0.5 or 2 s (hundreds of sub-steps): OK;
- diverging (the plant): u = 1e300 m/s2 over a 1 s step overflows the state: discard;
- warning (the plant): the hoist at 100 m/s2 reaches a cable limit (0.8 or 1.2 m) within a 1 s step:
  OK, with a warning message.

Every error status must come with an error message and no other status with one. The driver prints
the count per class; each class must be reached at least MINIMUM times. The Python, native and one-FMU
(a system of native models) kinds all answer through the one C framework. Discards and warnings come
only from the plant (the controllers and the planner have no state that can diverge and no limits
that warn), so they are required of the plant alone.
"""

import subprocess

import pytest
from helpers import compile_hosts, kind_folder, unpack_fmu

DRIVER = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static uint64_t rng;
static unsigned next(unsigned n) { rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17; return (unsigned)(rng % n); }
static long errors_logged, warnings_logged;
static char last_message[512];
static void *so;
#define SYM(name) ((name##TYPE *)dlsym(so, #name))
/* The shadow state machine: the mode the instance must be in, after FMI 2.0 section 4.2.4 / FMI 3.0 section 4.2. */
enum { INS, INI, STP, DSC, TRM, ERR };
static const char *const MODES[] = {"instantiated", "initialization", "step", "discarded", "terminated", "error"};
/* Each call's class, and the one status it must get. */
enum { VALID, WRONG_STATE, BAD_VALUE, LONG_STEP, DIVERGING, WARNING, N_CLASSES };
static const char *const CLASSES[] = {"valid", "wrong_state", "bad_value", "long_step", "diverging", "warning"};
static long counts[N_CLASSES];
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...) {
    va_list args;
    va_start(args, f);
    vsnprintf(last_message, sizeof last_message, f, args);
    va_end(args);
    if (s >= fmi2Discard) errors_logged++;
    if (s == fmi2Warning) warnings_logged++;
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
#define NEW() SYM(fmi2Instantiate)("fuzz", fmi2CoSimulation, token, resources, &cb, fmi2False, next(2))
#define FREE(c) SYM(fmi2FreeInstance)(c)
#define SET(vr, x) SYM(fmi2SetReal)(c, &(unsigned){vr}, 1, &(double){x})
#define GET(vr, out) SYM(fmi2GetReal)(c, &(unsigned){vr}, 1, out)
#define ENTER() SYM(fmi2EnterInitializationMode)(c)
#define EXIT() SYM(fmi2ExitInitializationMode)(c)
#define STEP(t, h) SYM(fmi2DoStep)(c, t, h, next(2))
#define TERMINATE() SYM(fmi2Terminate)(c)
#define RESET() SYM(fmi2Reset)(c)
#define GET_STATE(s) SYM(fmi2GetFMUstate)(c, s)
#define SET_STATE(s) SYM(fmi2SetFMUstate)(c, s)
#define FREE_STATE(s) SYM(fmi2FreeFMUstate)(c, s)
#define STATE_SIZE(s, n) SYM(fmi2SerializedFMUstateSize)(c, s, n)
#define SERIALIZE(s, out, n) SYM(fmi2SerializeFMUstate)(c, s, out, n)
#define DESERIALIZE(in, n, s) SYM(fmi2DeSerializeFMUstate)(c, in, n, s)
typedef fmi2FMUstate State;
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    snprintf(last_message, sizeof last_message, "%s", m);
    if (s >= fmi3Discard) errors_logged++;
    if (s == fmi3Warning) warnings_logged++;
}
#define NEW() SYM(fmi3InstantiateCoSimulation)("fuzz", token, resources, fmi3False, next(2), fmi3False, \
    fmi3False, NULL, 0, NULL, logger, NULL)
#define FREE(c) SYM(fmi3FreeInstance)(c)
#define SET(vr, x) SYM(fmi3SetFloat64)(c, &(unsigned){vr}, 1, &(double){x}, 1)
#define GET(vr, out) SYM(fmi3GetFloat64)(c, &(unsigned){vr}, 1, out, 1)
#define ENTER() SYM(fmi3EnterInitializationMode)(c, next(2), 1e-6, 0.0, next(2), 10.0)
#define EXIT() SYM(fmi3ExitInitializationMode)(c)
static fmi3Boolean flags[3];
static fmi3Float64 last;
#define STEP(t, h) SYM(fmi3DoStep)(c, t, h, next(2), flags, flags + 1, flags + 2, &last)
#define TERMINATE() SYM(fmi3Terminate)(c)
#define RESET() SYM(fmi3Reset)(c)
#define GET_STATE(s) SYM(fmi3GetFMUState)(c, s)
#define SET_STATE(s) SYM(fmi3SetFMUState)(c, s)
#define FREE_STATE(s) SYM(fmi3FreeFMUState)(c, s)
#define STATE_SIZE(s, n) SYM(fmi3SerializedFMUStateSize)(c, s, n)
#define SERIALIZE(s, out, n) SYM(fmi3SerializeFMUState)(c, s, (fmi3Byte *)out, n)
#define DESERIALIZE(in, n, s) SYM(fmi3DeserializeFMUState)(c, (const fmi3Byte *)in, n, s)
typedef fmi3FMUState State;
#endif
#define GETTABLE(m) ((m) != INS)
#define SETTABLE(m) ((m) == INS || (m) == INI || (m) == STP)

static void *c;
static long call_number;
static int op;
/* One call's status against the one its class allows; on a mismatch, say which and stop. */
static long errors_seen;
static void expect(int status, int expected, int cls, int mode) {
    if (getenv("TRACE")) fprintf(stderr, "%ld op %d %s %s -> %d\n", call_number, op, MODES[mode], CLASSES[cls], status);
    int said = errors_logged > errors_seen;
    errors_seen = errors_logged;
    if (status == expected && (status >= 2) == said) { counts[cls]++; return; }
    if (status != expected)
        printf("call %ld (op %d, class %s, instance %s): expected status %d, got %d (%s)\n", call_number, op,
               CLASSES[cls], MODES[mode], expected, status, said ? last_message : "no message");
    else
        printf("call %ld (op %d, class %s, instance %s): status %d %s\n", call_number, op, CLASSES[cls],
               MODES[mode], status, said ? "with an error message" : "without a message saying why");
    exit(5);
}

int main(int argc, char **argv) {
    /* library token resources seed calls, then name=value: in=VR (inputs, repeated), out=VR (calculated
       variables: outputs, Model Exchange states, derivatives and event indicators; repeated), get=VR (other
       reals to get, repeated), param=VR (refused NaN at the end of initialisation),
       default=VALUE (its default), for the plant u=VR hoist=VR l1_now=VR l1_min=VR l1_max=VR, and calm=1 for a
       system whose inputs are disturbances of its plant (set only to values near zero) */
    so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    const char *token = argv[2], *resources = argv[3];
    rng = strtoull(argv[4], NULL, 10) | 1;
    long calls = atol(argv[5]);
    unsigned in[64], out[64], get[64], param = 0, u = 0, hoist = 0, l1_now = 0, l1_min = 0, l1_max = 0;
    int n_in = 0, n_out = 0, n_get = 0, plant = 0, calm = 0;
    double param_default = 0.0;
    for (int i = 6; i < argc; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq) return 2;
        *eq = 0;
        const char *key = argv[i], *value = eq + 1;
        if (!strcmp(key, "in") && n_in < 64) in[n_in++] = atoi(value);
        else if (!strcmp(key, "out") && n_out < 64) out[n_out++] = atoi(value);
        else if (!strcmp(key, "get") && n_get < 64) get[n_get++] = atoi(value);
        else if (!strcmp(key, "param")) param = atoi(value);
        else if (!strcmp(key, "default")) param_default = atof(value);
        else if (!strcmp(key, "calm")) calm = atoi(value);
        else if (!strcmp(key, "u")) u = atoi(value), plant = 1;
        else if (!strcmp(key, "hoist")) hoist = atoi(value);
        else if (!strcmp(key, "l1_now")) l1_now = atoi(value);
        else if (!strcmp(key, "l1_min")) l1_min = atoi(value);
        else if (!strcmp(key, "l1_max")) l1_max = atoi(value);
        else return 2;
    }
    /* inputs the fuzzer sets with any value: every input of a controller; the plant's u, kept small so that
       only the diverging call diverges (hoist and forces are set by the warning call alone). Finite inputs
       near the largest double (1e308) are left out: the laws' arithmetic overflows on them and their
       outputs then fail with Python's math error, which no class here predicts. A system's inputs (hoist,
       forces on its plant) stay near zero: larger ones may make its closed loop diverge, which is the
       system's answer, not a class here. */
    static const double finite[] = {0.0, -0.0, 5e-324, 1e-3, 0.5, -1.0, 3.0, 1e6, -1e6, -1e-300};
    static const double small[] = {0.0, -0.0, 1e-3, 0.5, -1.0, 3.0, -3.0};
    static const double near_zero[] = {0.0, -0.0, 1e-3, -1e-3};
    static const double non_finite[] = {NAN, INFINITY, -INFINITY};
    static const double steps[] = {1e-3, 0.01, 0.1};
    static const double long_steps[] = {0.5, 2.0};
    static const double bad_steps[] = {0.0, -0.0, -1e-3, NAN, INFINITY, -INFINITY};
    int mode = INS, bad_param = 0, saved_mode = INS, saved_bad = 0;
    double now = 0.0, saved_now = 0.0, x;
    State state = NULL;
    char buffer[1 << 16], garbage[64];
    /* the plant's hoist runs between 0.8 and 1.2 m: each warning call drives it to one of the limits */
#define LIMITS() if (plant && (SET(l1_min, 0.8) || SET(l1_max, 1.2))) { printf("limits refused\n"); return 4; }
    c = NEW();
    if (!c) { fprintf(stderr, "instantiation failed\n"); return 4; }
    LIMITS();
    errors_seen = errors_logged;
    for (call_number = 0; call_number < calls; call_number++) {
        long warnings_before;
        int status, m = mode;
        op = next(18); /* 15-17: the plant's own calls (the others: an input) */
        if (next(5) == 0) op = mode == INS ? 1 : mode == INI ? 2 : mode == STP ? 7 : 10; /* move the session on */
        switch (op) {
        case 0: /* FMI 2.0: fmi2SetupExperiment; FMI 3.0: fmi3EnterInitializationMode */
#if FMI == 2
            status = SYM(fmi2SetupExperiment)(c, next(2), 1e-6, 0.0, next(2), 10.0);
            expect(status, m == INS ? 0 : 3, m == INS ? VALID : WRONG_STATE, m);
            break;
#endif
        case 1:
            status = ENTER();
            expect(status, m == INS ? 0 : 3, m == INS ? VALID : WRONG_STATE, m);
            if (m == INS) mode = INI, now = 0.0;
            break;
        case 2:
            status = EXIT();
            if (m != INI) expect(status, 3, WRONG_STATE, m);
            else if (bad_param) expect(status, 3, BAD_VALUE, m), mode = ERR;
            else expect(status, 0, VALID, m), mode = STP;
            break;
        case 3: /* an input, or the parameter judged at the end of initialisation */
            if (n_in == 0 || next(3) == 0) {
                if (m == STP) continue; /* a fixed parameter is not the fuzzer's business after initialisation */
                int nan = next(2);
                status = SET(param, nan ? NAN : param_default);
                expect(status, SETTABLE(m) ? 0 : 3, SETTABLE(m) ? VALID : WRONG_STATE, m);
                if (SETTABLE(m)) bad_param = nan;
                break;
            }
            /* fall through */
        case 4: {
            if (n_in == 0) continue;
            int bad = next(4) == 0;
            double value = bad ? non_finite[next(3)] : plant ? small[next(7)] : calm ? near_zero[next(4)]
                           : finite[next(10)];
            status = SET(plant ? u : in[next(n_in)], value);
            if (!SETTABLE(m)) expect(status, 3, WRONG_STATE, m);
            else if (bad) expect(status, 3, BAD_VALUE, m), mode = ERR;
            else expect(status, 0, VALID, m);
            break;
        }
        case 5: case 6: { /* a calculated variable is computed from the parameters: with a NaN one set,
                             before the initialisation ended, that fails */
            int k = next(n_out + n_get), output = k < n_out;
            status = GET(output ? out[k] : get[k - n_out], &x);
            if (!GETTABLE(m)) expect(status, 3, WRONG_STATE, m);
            else if (output && bad_param && (m == INI || m == ERR)) expect(status, 3, BAD_VALUE, m), mode = ERR;
            else expect(status, 0, VALID, m);
            break;
        }
        case 7: case 8: { /* a step: usual, long, or of a size no step may have */
            int kind = next(4);
            double h = kind < 2 ? steps[next(3)] : kind == 2 ? long_steps[next(2)] : bad_steps[next(6)];
            if (kind == 3 && plant && next(3) == 0) h = 1e300; /* more than 10^7 RK4 sub-steps: refused */
            status = STEP(now, h);
            if (m != STP) expect(status, 3, WRONG_STATE, m);
            else if (kind == 3) expect(status, 3, BAD_VALUE, m), mode = ERR;
            else expect(status, 0, kind == 2 ? LONG_STEP : VALID, m), now += h;
            break;
        }
        case 9:
            status = TERMINATE();
            expect(status, m == STP || m == DSC ? 0 : 3, m == STP || m == DSC ? VALID : WRONG_STATE, m);
            if (m == STP || m == DSC) mode = TRM;
            break;
        case 10:
            expect(RESET(), 0, VALID, m);
            mode = INS, bad_param = 0, now = 0.0;
            LIMITS();
            break;
        case 11:
            if (state) FREE_STATE(&state);
            expect(GET_STATE(&state), 0, VALID, m);
            saved_mode = mode, saved_bad = bad_param, saved_now = now;
            break;
        case 12:
            if (!state) continue;
            expect(SET_STATE(state), 0, VALID, m);
            mode = saved_mode, bad_param = saved_bad, now = saved_now;
            break;
        case 13: { /* a saved state serialised and read back */
            size_t n = 0;
            State copy = NULL;
            if (!state) continue;
            expect(STATE_SIZE(state, &n), 0, VALID, m);
            if (n > sizeof buffer) { printf("serialised state too large: %zu\n", n); return 4; }
            expect(SERIALIZE(state, buffer, n), 0, VALID, m);
            expect(DESERIALIZE(buffer, n, &copy), 0, VALID, m);
            expect(FREE_STATE(&copy), 0, VALID, m);
            break;
        }
        case 14: /* garbage is not a serialised state: refused, the instance as it was */
            for (int i = 0; i < 64; i++) garbage[i] = (char)next(256);
            status = DESERIALIZE(garbage, next(64), &state);
            expect(status, 3, BAD_VALUE, m);
            break;
        default: /* the plant: a diverging step or a hoist limit; the others: draw again */
            if (!plant) { call_number--; continue; }
            if (m != STP) { expect(STEP(now, 1.0), 3, WRONG_STATE, m); break; }
            if (next(2)) { /* u = 1e300 m/s2: the state overflows within the step, which is discarded */
                expect(SET(u, 1e300), 0, VALID, m);
                expect(STEP(now, 1.0), 2, DIVERGING, m);
                mode = DSC;
            } else { /* the hoist at 100 m/s2 reaches a limit within the step: OK, with a warning */
                expect(GET(l1_now, &x), 0, VALID, m);
                expect(SET(hoist, x >= 1.0 ? -100.0 : 100.0), 0, VALID, m);
                warnings_before = warnings_logged;
                status = STEP(now, 1.0);
                if (status == 0 && warnings_logged == warnings_before) {
                    printf("call %ld: the hoist reached its limit without a warning\n", call_number);
                    return 5;
                }
                expect(status, 0, WARNING, m);
                now += 1.0;
            }
            break;
        }
        if (next(200) == 0) { /* free everything and start again */
            if (state) FREE_STATE(&state);
            state = NULL;
            FREE(c);
            c = NEW();
            if (!c) { printf("instantiation failed again\n"); return 4; }
            mode = INS, bad_param = 0, now = 0.0;
            LIMITS();
            errors_seen = errors_logged;
        }
    }
    if (state) FREE_STATE(&state);
    FREE(c);
    for (int k = 0; k < N_CLASSES; k++) printf("%s %ld%s", CLASSES[k], counts[k], k + 1 < N_CLASSES ? " " : "\n");
    return 0;
}
"""

CLASSES = ("valid", "wrong_state", "bad_value", "long_step", "diverging", "warning")
MINIMUM = 20  # per class and run: every path taken many times, not once by luck


@pytest.fixture(scope="module")
def drivers(tmp_path_factory):
    return compile_hosts(DRIVER, tmp_path_factory.mktemp("fuzz"))


MODELS = ["CranePlant", "LqrController", "BacksteppingController", "TrajectoryPlanner"]
# every kind of FMU over the one C framework: the Python model, the native models, a system of them as one FMU
FMUS = [("python", name) for name in MODELS] + [("native", name) for name in MODELS] + [("one-fmu", "CraneLqr")]


@pytest.mark.parametrize(("kind", "name"), FMUS)
@pytest.mark.parametrize("version", [2, 3])
def test_random_calls_from_a_c_host_get_the_status_their_class_requires(drivers, fmu_dir, kind, name, version,
                                                                       tmp_path, request):
    fmu = kind_folder(request, fmu_dir, kind, version) / f"{name}.fmu"
    md, library, token, resources = unpack_fmu(fmu, tmp_path)
    reals = {v.name: v for v in md.modelVariables if v.type in ("Real", "Float64")}
    args = [f"in={v.valueReference}" for v in reals.values() if v.causality == "input"]
    # calculated (initial="calculated"): the outputs, and a Model Exchange FMU's states, derivatives and event
    # indicators, which the FMU computes from the parameters as it does its outputs; the others are stored
    calculated = [v.causality == "output" or v.initial == "calculated" for v in reals.values()]
    args += [f"{'out' if c else 'get'}={v.valueReference}" for c, v in zip(calculated, reals.values())]
    param = reals["m1" if "m1" in reals else "x_d"]  # refused as NaN when initialisation ends
    args += [f"param={param.valueReference}", f"default={float(param.start)!r}"]
    plant = name == "CranePlant"
    if plant:
        args += [f"{n}={reals[n].valueReference}" for n in ("u", "hoist", "l1_now", "l1_min", "l1_max")]
    if kind == "one-fmu":
        args.append("calm=1")
    proc = subprocess.run([str(drivers[version]), library, token, resources, "12345", "4000", *args],
                          capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert proc.returncode == 0, f"status {proc.returncode}: {proc.stdout[-2000:]} {proc.stderr[-2000:]}"
    words = proc.stdout.split()
    counts = dict(zip(words[::2], map(int, words[1::2])))
    print(f"FMI {version}.0 {kind} {name}:", counts)
    required = CLASSES if plant else CLASSES[:4]
    assert all(counts[k] >= MINIMUM for k in required), (f"fewer than {MINIMUM} calls in a class", counts)
    assert plant or counts["diverging"] == counts["warning"] == 0, counts
