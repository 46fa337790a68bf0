"""The FMI state machine of our C wrappers as a table, like Reference-FMUs' state masks.

A C host (compiled per FMI version against the official headers) drives a fresh instance (the Python
CranePlant, the native one and a native closed loop as one FMU: all answer through the one C framework,
fmu_src/framework) into each state, calls one exported function there with valid arguments, and reports the status.
It then checks that the instance is still usable: from the state the call should have left it in
(the same state after a refusal) it runs the rest of a session, every call of which must give OK.

The allowed states are written here, from the standards' tables: FMI 2.0 section 4.2.4 (the state
table of co-simulation; the masks of the Reference FMUs are the same) and FMI 3.0 section 4.2
(co-simulation without event mode). What this FMU adds to the standards, stated per entry:

- a refused call (wrong state, bad argument) leaves the instance in the state it was in, so a host
  may go on; the standard leaves the instance's state after an error to the FMU, and asks only that
  fmi2Reset (fmi3Reset) recover it, which the continuations from the error state check;
- FMI 3.0 names no state for "after a discarded step"; like FMI 2.0's stepFailed it allows gets,
  FMU states, terminate and reset, and refuses further steps;
- FMI 3.0's error state allows what FMI 2.0's does (gets for diagnosis, FMU states, reset);
- the functions the FMU does not provide (capability flags false, no event mode, no clocks, no types other
  than Float64, Int32, Int64, UInt64, Boolean, String), and those of Model Exchange on a co-simulation
  instance, answer fmi2Error (fmi3Error) with a message in every state.

A second host drives the native plant as a Model Exchange instance through its modes (instantiated,
initialization, event mode, continuous-time mode, terminated, error) against FMI 2.0's Model Exchange table
(section 3.2.3) and FMI 3.0's common states (section 2.3). Where the two standards differ, each version
follows its own: FMI 2.0 gives the derivatives from event mode on and the nominals also when instantiated,
FMI 3.0 both from initialization mode on. Reference-FMUs' FMI 2.0 masks are the same as the FMI 2.0 table.
"""

import subprocess

import pytest
from helpers import compile_hosts, kind_folder, unpack_fmu

HOST = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static void *so, *c;
static unsigned vr_u, vr_x, vr_setup;
static double setup_value, push;
static double now;
static int errors_logged;
#define CALL(name, ...) ((name##TYPE *)dlsym(so, #name))(__VA_ARGS__)
#define IS(name) (!strcmp(f, name))
enum { INSTANTIATED, INITIALIZATION, STEP, DISCARDED, TERMINATED, ERROR };
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String cat, fmi2String m, ...) {
    if (s >= fmi2Error) errors_logged++;
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
#define NEW() CALL(fmi2Instantiate, "table", fmi2CoSimulation, token, resources, &cb, fmi2False, fmi2False)
#define FREE() CALL(fmi2FreeInstance, c)
#define SET_REAL(vr, value) CALL(fmi2SetReal, c, &(unsigned){vr}, 1, &(double){value})
#define GET_REAL(vr, out) CALL(fmi2GetReal, c, &(unsigned){vr}, 1, out)
#define ENTER() (CALL(fmi2SetupExperiment, c, 0, 0.0, 0.0, 0, 0.0) || CALL(fmi2EnterInitializationMode, c))
#define EXIT() CALL(fmi2ExitInitializationMode, c)
#define STEP_BY(h) CALL(fmi2DoStep, c, now, h, fmi2True)
#define TERMINATE() CALL(fmi2Terminate, c)
#define RESET() CALL(fmi2Reset, c)
typedef fmi2FMUstate State;
#define GET_STATE(s) CALL(fmi2GetFMUstate, c, s)
#define SET_STATE(s) CALL(fmi2SetFMUstate, c, s)
#define FREE_STATE(s) CALL(fmi2FreeFMUstate, c, s)
#define STATE_SIZE(s, n) CALL(fmi2SerializedFMUstateSize, c, s, n)
#define SERIALIZE(s, out, n) CALL(fmi2SerializeFMUstate, c, s, out, n)
#define DESERIALIZE(in, n, s) CALL(fmi2DeSerializeFMUstate, c, in, n, s)
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String cat, fmi3String m) {
    if (s >= fmi3Error) errors_logged++;
}
#define NEW() CALL(fmi3InstantiateCoSimulation, "table", token, resources, fmi3False, fmi3False, fmi3False, \
                   fmi3False, NULL, 0, NULL, logger, NULL)
#define FREE() CALL(fmi3FreeInstance, c)
#define SET_REAL(vr, value) CALL(fmi3SetFloat64, c, &(unsigned){vr}, 1, &(double){value}, 1)
#define GET_REAL(vr, out) CALL(fmi3GetFloat64, c, &(unsigned){vr}, 1, out, 1)
#define ENTER() CALL(fmi3EnterInitializationMode, c, fmi3False, 0.0, 0.0, fmi3False, 0.0)
#define EXIT() CALL(fmi3ExitInitializationMode, c)
static fmi3Boolean flag;
static fmi3Float64 last;
#define STEP_BY(h) CALL(fmi3DoStep, c, now, h, fmi3True, &flag, &flag, &flag, &last)
#define TERMINATE() CALL(fmi3Terminate, c)
#define RESET() CALL(fmi3Reset, c)
typedef fmi3FMUState State;
#define GET_STATE(s) CALL(fmi3GetFMUState, c, s)
#define SET_STATE(s) CALL(fmi3SetFMUState, c, s)
#define FREE_STATE(s) CALL(fmi3FreeFMUState, c, s)
#define STATE_SIZE(s, n) CALL(fmi3SerializedFMUStateSize, c, s, n)
#define SERIALIZE(s, out, n) CALL(fmi3SerializeFMUState, c, s, (fmi3Byte *)out, n)
#define DESERIALIZE(in, n, s) CALL(fmi3DeserializeFMUState, c, (const fmi3Byte *)in, n, s)
#endif

/* Drive the fresh instance into `state`; 0 on success. The setup value (the plant: a rail end x_max = 0.3 m)
   and the input at `push` (the plant: u = 1 m/s2; a closed loop: a force of 1e300 N) make a 2 s step a
   discarded step; a NaN input is refused with an error. */
static int reach(int state) {
    now = 0.0;
    if (SET_REAL(vr_setup, setup_value)) return 1;
    if (state == INSTANTIATED) return 0;
    if (ENTER()) return 1;
    if (state == INITIALIZATION) return 0;
    if (EXIT()) return 1;
    if (state == STEP) return 0;
    if (state == DISCARDED) return SET_REAL(vr_u, push) || STEP_BY(2.0) != 2;
    if (state == TERMINATED) return TERMINATE() != 0;
    return SET_REAL(vr_u, NAN) != 3;
}

/* The rest of a session from `state`, each call expected to give OK: 0, or the number of the call that did not. */
static int go_on(int state) {
    double x;
    int k = 1;
    switch (state) {
    case TERMINATED: if (GET_REAL(vr_x, &x)) return k; k++; /* fall through: reset, then a whole session */
    case ERROR: if (RESET()) return k; k++; now = 0.0; /* fall through */
    case INSTANTIATED: if (ENTER()) return k; k++; /* fall through */
    case INITIALIZATION: if (EXIT()) return k; k++; /* fall through */
    case STEP: if (STEP_BY(1e-3)) return k; k++; now += 1e-3; if (GET_REAL(vr_x, &x)) return k; k++;
               /* fall through */
    case DISCARDED: if (TERMINATE()) return k; k++;
    }
    return 0;
}

/* The function named f, in the current state, with valid arguments (n = 0 for types the FMU has none of). */
static int call(const char *f, int *next) {
    double x = 0.0;
    size_t n = 0;
    char buffer[1 << 16];
    State s = NULL, t = NULL;
    int status = -1;
    if (IS("GetFMUstate") || IS("GetFMUState")) {
        status = GET_STATE(&s);
        if (!status) FREE_STATE(&s);
        return status;
    }
    if (IS("SetFMUstate") || IS("SetFMUState") || IS("FreeFMUstate") || IS("FreeFMUState") ||
        IS("SerializedFMUstateSize") || IS("SerializedFMUStateSize") || IS("SerializeFMUstate") ||
        IS("SerializeFMUState") || IS("DeSerializeFMUstate") || IS("DeserializeFMUState")) {
        if (GET_STATE(&s)) return 100; /* the state needed for the call was not given */
        if (IS("SetFMUstate") || IS("SetFMUState")) status = SET_STATE(s);
        else if (IS("FreeFMUstate") || IS("FreeFMUState")) return FREE_STATE(&s);
        else if (IS("SerializedFMUstateSize") || IS("SerializedFMUStateSize")) status = STATE_SIZE(s, &n);
        else {
            if (STATE_SIZE(s, &n) || n > sizeof buffer) return 101;
            status = SERIALIZE(s, buffer, n);
            if (!status && (IS("DeSerializeFMUstate") || IS("DeserializeFMUState"))) {
                status = DESERIALIZE(buffer, n, &t);
                if (!status) FREE_STATE(&t);
            }
        }
        FREE_STATE(&s);
        return status;
    }
    if (IS("DoStep")) { status = STEP_BY(1e-3); if (!status) now += 1e-3; return status; }
    if (IS("ExitInitializationMode")) return EXIT();
    if (IS("Terminate")) return TERMINATE();
    if (IS("Reset")) { now = 0.0; return RESET(); }
#if FMI == 2
    fmi2Integer i = 0;
    fmi2Boolean b = 0;
    fmi2String str = NULL;
    fmi2Status st;
    if (IS("SetDebugLogging")) return CALL(fmi2SetDebugLogging, c, fmi2False, 0, NULL);
    if (IS("SetupExperiment")) return CALL(fmi2SetupExperiment, c, 0, 0.0, 0.0, 0, 0.0);
    if (IS("EnterInitializationMode")) return CALL(fmi2EnterInitializationMode, c);
    if (IS("GetReal")) return GET_REAL(vr_x, &x);
    if (IS("SetReal")) return SET_REAL(vr_u, 0.0);
    if (IS("GetInteger")) return CALL(fmi2GetInteger, c, NULL, 0, &i);
    if (IS("SetInteger")) return CALL(fmi2SetInteger, c, NULL, 0, &i);
    if (IS("GetBoolean")) return CALL(fmi2GetBoolean, c, NULL, 0, &b);
    if (IS("SetBoolean")) return CALL(fmi2SetBoolean, c, NULL, 0, &b);
    if (IS("GetString")) return CALL(fmi2GetString, c, NULL, 0, &str);
    if (IS("SetString")) return CALL(fmi2SetString, c, NULL, 0, &str);
    if (IS("GetRealStatus")) return CALL(fmi2GetRealStatus, c, fmi2LastSuccessfulTime, &x);
    if (IS("GetBooleanStatus")) return CALL(fmi2GetBooleanStatus, c, fmi2Terminated, &b);
    /* not provided */
    if (IS("GetDirectionalDerivative")) return CALL(fmi2GetDirectionalDerivative, c, NULL, 0, NULL, 0, NULL, NULL);
    if (IS("SetRealInputDerivatives")) return CALL(fmi2SetRealInputDerivatives, c, NULL, 0, NULL, NULL);
    if (IS("GetRealOutputDerivatives")) return CALL(fmi2GetRealOutputDerivatives, c, NULL, 0, NULL, NULL);
    if (IS("CancelStep")) return CALL(fmi2CancelStep, c);
    if (IS("GetStatus")) return CALL(fmi2GetStatus, c, fmi2DoStepStatus, &st);
    if (IS("GetIntegerStatus")) return CALL(fmi2GetIntegerStatus, c, fmi2LastSuccessfulTime, &i);
    if (IS("GetStringStatus")) return CALL(fmi2GetStringStatus, c, fmi2PendingStatus, &str);
    /* Model Exchange, exported by an FMU that has both interfaces: no call of a co-simulation instance */
    fmi2EventInfo info;
    if (IS("EnterEventMode")) return CALL(fmi2EnterEventMode, c);
    if (IS("NewDiscreteStates")) return CALL(fmi2NewDiscreteStates, c, &info);
    if (IS("EnterContinuousTimeMode")) return CALL(fmi2EnterContinuousTimeMode, c);
    if (IS("CompletedIntegratorStep")) return CALL(fmi2CompletedIntegratorStep, c, fmi2True, &b, &b);
    if (IS("SetTime")) return CALL(fmi2SetTime, c, 0.0);
    if (IS("SetContinuousStates")) return CALL(fmi2SetContinuousStates, c, NULL, 0);
    if (IS("GetDerivatives")) return CALL(fmi2GetDerivatives, c, NULL, 0);
    if (IS("GetEventIndicators")) return CALL(fmi2GetEventIndicators, c, NULL, 0);
    if (IS("GetContinuousStates")) return CALL(fmi2GetContinuousStates, c, NULL, 0);
    if (IS("GetNominalsOfContinuousStates")) return CALL(fmi2GetNominalsOfContinuousStates, c, NULL, 0);
#else
    fmi3Int32 i32 = 0;
    fmi3Int64 i64 = 0;
    fmi3UInt64 u64 = 0;
    fmi3Boolean b = 0;
    fmi3String str = NULL;
    fmi3Float64 d = 0.0;
    if (IS("SetDebugLogging")) return CALL(fmi3SetDebugLogging, c, fmi3False, 0, NULL);
    if (IS("EnterInitializationMode")) return ENTER();
    if (IS("GetFloat64")) return GET_REAL(vr_x, &x);
    if (IS("SetFloat64")) return SET_REAL(vr_u, 0.0);
    if (IS("GetInt32")) return CALL(fmi3GetInt32, c, NULL, 0, &i32, 0);
    if (IS("SetInt32")) return CALL(fmi3SetInt32, c, NULL, 0, &i32, 0);
    if (IS("GetInt64")) return CALL(fmi3GetInt64, c, NULL, 0, &i64, 0);
    if (IS("SetInt64")) return CALL(fmi3SetInt64, c, NULL, 0, &i64, 0);
    if (IS("GetUInt64")) return CALL(fmi3GetUInt64, c, NULL, 0, &u64, 0);
    if (IS("SetUInt64")) return CALL(fmi3SetUInt64, c, NULL, 0, &u64, 0);
    if (IS("GetBoolean")) return CALL(fmi3GetBoolean, c, NULL, 0, &b, 0);
    if (IS("SetBoolean")) return CALL(fmi3SetBoolean, c, NULL, 0, &b, 0);
    if (IS("GetString")) return CALL(fmi3GetString, c, NULL, 0, &str, 0);
    if (IS("SetString")) return CALL(fmi3SetString, c, NULL, 0, &str, 0);
    /* not provided */
#define VALUES(Type) if (IS("Get" #Type)) return CALL(fmi3Get##Type, c, NULL, 0, NULL, 0); \
                     if (IS("Set" #Type)) return CALL(fmi3Set##Type, c, NULL, 0, NULL, 0);
    VALUES(Float32) VALUES(Int8) VALUES(UInt8) VALUES(Int16) VALUES(UInt16) VALUES(UInt32)
    if (IS("GetBinary")) return CALL(fmi3GetBinary, c, NULL, 0, NULL, NULL, 0);
    if (IS("SetBinary")) return CALL(fmi3SetBinary, c, NULL, 0, NULL, NULL, 0);
    if (IS("GetClock")) return CALL(fmi3GetClock, c, NULL, 0, NULL);
    if (IS("SetClock")) return CALL(fmi3SetClock, c, NULL, 0, NULL);
    if (IS("EnterEventMode")) return CALL(fmi3EnterEventMode, c);
    if (IS("GetNumberOfVariableDependencies")) return CALL(fmi3GetNumberOfVariableDependencies, c, vr_x, &n);
    if (IS("GetVariableDependencies"))
        return CALL(fmi3GetVariableDependencies, c, vr_x, NULL, NULL, NULL, NULL, 0);
    if (IS("GetDirectionalDerivative"))
        return CALL(fmi3GetDirectionalDerivative, c, NULL, 0, NULL, 0, NULL, 0, NULL, 0);
    if (IS("GetAdjointDerivative")) return CALL(fmi3GetAdjointDerivative, c, NULL, 0, NULL, 0, NULL, 0, NULL, 0);
    if (IS("EnterConfigurationMode")) return CALL(fmi3EnterConfigurationMode, c);
    if (IS("ExitConfigurationMode")) return CALL(fmi3ExitConfigurationMode, c);
    if (IS("GetIntervalDecimal")) return CALL(fmi3GetIntervalDecimal, c, NULL, 0, NULL, NULL);
    if (IS("GetIntervalFraction")) return CALL(fmi3GetIntervalFraction, c, NULL, 0, NULL, NULL, NULL);
    if (IS("GetShiftDecimal")) return CALL(fmi3GetShiftDecimal, c, NULL, 0, NULL);
    if (IS("GetShiftFraction")) return CALL(fmi3GetShiftFraction, c, NULL, 0, NULL, NULL);
    if (IS("SetIntervalDecimal")) return CALL(fmi3SetIntervalDecimal, c, NULL, 0, NULL);
    if (IS("SetIntervalFraction")) return CALL(fmi3SetIntervalFraction, c, NULL, 0, NULL, NULL);
    if (IS("SetShiftDecimal")) return CALL(fmi3SetShiftDecimal, c, NULL, 0, NULL);
    if (IS("SetShiftFraction")) return CALL(fmi3SetShiftFraction, c, NULL, 0, NULL, NULL);
    if (IS("EvaluateDiscreteStates")) return CALL(fmi3EvaluateDiscreteStates, c);
    if (IS("UpdateDiscreteStates")) return CALL(fmi3UpdateDiscreteStates, c, &b, &b, &b, &b, &b, &d);
    if (IS("EnterContinuousTimeMode")) return CALL(fmi3EnterContinuousTimeMode, c);
    if (IS("CompletedIntegratorStep")) return CALL(fmi3CompletedIntegratorStep, c, fmi3True, &b, &b);
    if (IS("SetTime")) return CALL(fmi3SetTime, c, 0.0);
    if (IS("SetContinuousStates")) return CALL(fmi3SetContinuousStates, c, NULL, 0);
    if (IS("GetContinuousStateDerivatives")) return CALL(fmi3GetContinuousStateDerivatives, c, NULL, 0);
    if (IS("GetEventIndicators")) return CALL(fmi3GetEventIndicators, c, NULL, 0);
    if (IS("GetContinuousStates")) return CALL(fmi3GetContinuousStates, c, NULL, 0);
    if (IS("GetNominalsOfContinuousStates")) return CALL(fmi3GetNominalsOfContinuousStates, c, NULL, 0);
    if (IS("GetNumberOfEventIndicators")) return CALL(fmi3GetNumberOfEventIndicators, c, &n);
    if (IS("GetNumberOfContinuousStates")) return CALL(fmi3GetNumberOfContinuousStates, c, &n);
    if (IS("EnterStepMode")) return CALL(fmi3EnterStepMode, c);
    if (IS("GetOutputDerivatives")) return CALL(fmi3GetOutputDerivatives, c, NULL, 0, NULL, NULL, 0);
    if (IS("ActivateModelPartition")) return CALL(fmi3ActivateModelPartition, c, 0, 0.0);
#endif
    return 200; /* no such function in this host */
}

int main(int argc, char **argv) {
    /* library token resources vr_u vr_x vr_setup setup_value push; stdin: lines "function state next-state-if-ok" */
    so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    const char *token = argv[2], *resources = argv[3];
    vr_u = atoi(argv[4]), vr_x = atoi(argv[5]), vr_setup = atoi(argv[6]);
    setup_value = atof(argv[7]), push = atof(argv[8]);
#if FMI == 2
    if (strcmp(CALL(fmi2GetVersion), "2.0") || strcmp(CALL(fmi2GetTypesPlatform), "default")) return 7;
#else
    if (strcmp(CALL(fmi3GetVersion), "3.0")) return 7;
#endif
    char f[128];
    int state, next;
    while (scanf("%127s %d %d", f, &state, &next) == 3) {
        c = NEW();
        if (!c) { printf("%s %d instantiation-failed\n", f, state); continue; }
        if (reach(state)) { printf("%s %d reach-failed\n", f, state); FREE(); continue; }
        int before = errors_logged;
        int status = call(f, &next);
        int silent = status >= 3 && errors_logged == before;
        int failed_call = go_on(status == 0 ? next : state);
        printf("%s %d status=%d%s continuation=%d\n", f, state, status, silent ? " silent" : "", failed_call);
        FREE(); /* fmiFreeInstance in every state */
    }
    return 0;
}
"""

STATES = ("instantiated", "initialization", "step", "discarded", "terminated", "error")
INS, INI, STP, DSC, TRM, ERR = range(6)
EVERY = {INS, INI, STP, DSC, TRM, ERR}
GETS = {INI, STP, DSC, TRM, ERR}  # FMI 2.0 table: gets from initialization mode on, in error for diagnosis
SETS = {INS, INI, STP}  # FMI 2.0 table: start values, initialisation, inputs between steps
# the rest of a session from each state, as the host's go_on() runs it (each call must give OK)
REST = {INS: ["EnterInitializationMode", "ExitInitializationMode", "DoStep", "GetReal", "Terminate"]}
REST[INI], REST[STP], REST[DSC] = REST[INS][1:], REST[INS][2:], ["Terminate"]
REST[ERR] = ["Reset"] + REST[INS]
REST[TRM] = ["GetReal"] + REST[ERR]
STATE_FUNCTIONS = {"GetFMUstate", "SetFMUstate", "FreeFMUstate", "SerializedFMUstateSize", "SerializeFMUstate",
                   "DeSerializeFMUstate"}

# function: (the states it is allowed in, the state it leaves on OK when it changes the state)
FMI2 = {
    "SetDebugLogging": (EVERY, None), "SetupExperiment": ({INS}, None), "EnterInitializationMode": ({INS}, INI),
    "ExitInitializationMode": ({INI}, STP), "Terminate": ({STP, DSC}, TRM), "Reset": (EVERY, INS),
    **{f"Get{t}": (GETS, None) for t in ("Real", "Integer", "Boolean", "String")},
    **{f"Set{t}": (SETS, None) for t in ("Real", "Integer", "Boolean", "String")},
    **{f: (EVERY, None) for f in STATE_FUNCTIONS},
    "DoStep": ({STP}, STP), "GetRealStatus": ({STP, DSC, TRM}, None), "GetBooleanStatus": ({STP, DSC, TRM}, None),
    **{f: (set(), None) for f in ("GetDirectionalDerivative", "SetRealInputDerivatives", "GetRealOutputDerivatives",
                                  "CancelStep", "GetStatus", "GetIntegerStatus", "GetStringStatus")},
}
# FMI 2.0 has one set of functions for both interfaces: an FMU that declares <ModelExchange> beside
# <CoSimulation> exports the Model Exchange functions too (the native CranePlant), and so does a closed loop as
# one FMU (its framework is the plant's). They are no part of the
# co-simulation state machine (section 4.2.4 has no row for them; they belong to the Model Exchange one,
# section 3.2.3, whose modes a co-simulation instance never enters), so a co-simulation instance refuses them
# in every state. (FMI 3.0's table above lists its Model Exchange functions already, refused alike.)
FMI2_MODEL_EXCHANGE = {f: (set(), None) for f in (
    "EnterEventMode", "NewDiscreteStates", "EnterContinuousTimeMode", "CompletedIntegratorStep", "SetTime",
    "SetContinuousStates", "GetDerivatives", "GetEventIndicators", "GetContinuousStates",
    "GetNominalsOfContinuousStates")}
# The directional (FMI 3.0: and adjoint) derivatives of an FMU that provides them in co-simulation (FMI 2.0
# providesDirectionalDerivative, FMI 3.0 providesDirectionalDerivatives and providesAdjointDerivatives on
# <CoSimulation>): as the gets (FMI 2.0's table; FMI 3.0 section 2.3: Initialization Mode, Step Mode, Terminated).
CO_SIMULATION_DERIVATIVES = {2: {"GetDirectionalDerivative": (GETS, None)},
                             3: {"GetDirectionalDerivative": (GETS, None), "GetAdjointDerivative": (GETS, None)}}
FMI3_TYPES = ("Float64", "Int32", "Int64", "UInt64", "Boolean", "String", "Float32", "Int8", "UInt8", "Int16",
              "UInt16", "UInt32")
FMI3 = {
    "SetDebugLogging": (EVERY, None), "EnterInitializationMode": ({INS}, INI), "ExitInitializationMode": ({INI}, STP),
    "Terminate": ({STP, DSC}, TRM), "Reset": (EVERY, INS),
    **{f"Get{t}": (GETS, None) for t in FMI3_TYPES}, **{f"Set{t}": (SETS, None) for t in FMI3_TYPES},
    **{f.replace("state", "State").replace("DeSerialize", "Deserialize"): (EVERY, None) for f in STATE_FUNCTIONS},
    "DoStep": ({STP}, STP),
    **{f"{verb}{t}": (set(), None) for verb in ("Get", "Set")
       for t in ("Binary", "Clock")},
    **{f: (set(), None) for f in (
        "EnterEventMode", "GetNumberOfVariableDependencies", "GetVariableDependencies", "GetDirectionalDerivative",
        "GetAdjointDerivative", "EnterConfigurationMode", "ExitConfigurationMode", "GetIntervalDecimal",
        "GetIntervalFraction", "GetShiftDecimal", "GetShiftFraction", "SetIntervalDecimal", "SetIntervalFraction",
        "SetShiftDecimal", "SetShiftFraction", "EvaluateDiscreteStates", "UpdateDiscreteStates",
        "EnterContinuousTimeMode", "CompletedIntegratorStep", "SetTime", "SetContinuousStates",
        "GetContinuousStateDerivatives", "GetEventIndicators", "GetContinuousStates", "GetNominalsOfContinuousStates",
        "GetNumberOfEventIndicators", "GetNumberOfContinuousStates", "EnterStepMode", "GetOutputDerivatives",
        "ActivateModelPartition")},
}


@pytest.fixture(scope="module")
def table_hosts(tmp_path_factory):
    return compile_hosts(HOST, tmp_path_factory.mktemp("states"))


def _exported(library, prefix):
    """The FMI functions the library exports (its dynamic symbol table)."""
    symbols = subprocess.run(["nm", "-D", "--defined-only", library], capture_output=True, text=True,
                             check=True).stdout.split()
    return {s.removeprefix(prefix) for s in symbols if s.startswith(prefix)}


# every kind of FMU over the one C framework: the Python model, the native model (with Model Exchange beside
# co-simulation), a closed loop as one FMU; each with (the input set, the knob set when instantiated and its value,
# the input value that makes a 2 s step discarded)
FMUS = {("python", "CranePlant"): ("u", "x_max", 0.3, 1.0), ("native", "CranePlant"): ("u", "x_max", 0.3, 1.0),
        ("one-fmu", "CraneLqr"): ("F1", "x_d", 1.0, 1e300)}


@pytest.mark.parametrize(("kind", "name"), FMUS)
@pytest.mark.parametrize("version", [2, 3])
def test_every_function_in_every_state_gets_the_status_of_the_standards_table(table_hosts, fmu_dir, version, kind,
                                                                              name, tmp_path, request):
    """Each (function, state) pair: OK where the table allows it, else fmi2Error/fmi3Error with a message;
    and the instance goes on: after OK from the state the call leads to, after a refusal from the same state.

    fmi2DoStep (fmi3DoStep) in initialization mode must be refused here, by the C wrapper: this host calls
    the binary directly, with no Python master in between.
    """
    prefix = f"fmi{version}"
    fmu = kind_folder(request, fmu_dir, kind, version) / f"{name}.fmu"
    md, library, token, resources = unpack_fmu(fmu, tmp_path)
    # every function the FMU exports is in the table, except those called once per process or instance
    lifecycle = {"GetVersion", "GetTypesPlatform", "Instantiate", "InstantiateCoSimulation",
                 "InstantiateModelExchange", "InstantiateScheduledExecution", "FreeInstance"}
    exported = _exported(library, prefix) - lifecycle
    model_exchange = md.modelExchange or exported & set(FMI2_MODEL_EXCHANGE)
    table = FMI3 if version == 3 else FMI2 | FMI2_MODEL_EXCHANGE if model_exchange else FMI2
    if md.modelExchange:  # an FMU with Model Exchange (the native plant) gives its derivatives in co-simulation too
        table = table | CO_SIMULATION_DERIVATIVES[version]
    assert exported == set(table)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    cases = [(f, s) for f in table for s in range(6)]
    stdin = "".join(f"{f} {s} {table[f][1] if table[f][1] is not None else s}\n" for f, s in cases)
    pushed, setup, setup_value, push = FMUS[kind, name]
    proc = subprocess.run([str(table_hosts[version]), library, token, resources, str(vr[pushed]), str(vr["x"]),
                           str(vr[setup]), repr(setup_value), repr(push)], input=stdin, capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert len(lines) == len(cases), proc.stdout[-2000:]
    wrong = []
    for (f, s), line in zip(cases, lines):
        expected = 0 if s in table[f][0] else 3
        if line != f"{f} {s} status={expected} continuation=0":
            got = line.split(" ", 2)[2]
            status, _, failed = got.rpartition(" continuation=")
            start = s if status != "status=0" or table[f][1] is None else table[f][1]
            then = (f", then from {STATES[start]} {prefix}{REST[start][int(failed) - 1]} failed" if failed.isdigit()
                    and int(failed) > 0 else "")
            wrong.append(f"{prefix}{f} when {STATES[s]}: expected status {expected}, got {status}{then}")
    assert not wrong, "\n".join(wrong)


# ---- Model Exchange: an instance the host integrates ----------------------------------------------------------------

ME_HOST = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static void *so, *c;
static unsigned vr_u, vr_x, vr_state, vr_derivative;
static int errors_logged;
enum { NX = 9, NZ = 8 };
static const double STATES[NX] = {0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0}; /* at rest, swung, l1 = 1 m */
#define CALL(name, ...) ((name##TYPE *)dlsym(so, #name))(__VA_ARGS__)
#define IS(name) (!strcmp(f, name))
enum { INSTANTIATED, INITIALIZATION, EVENT, CONTINUOUS, TERMINATED, ERROR };
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String cat, fmi2String m, ...) {
    if (s >= fmi2Error) errors_logged++;
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
static fmi2EventInfo info;
static fmi2Boolean flag;
#define NEW() CALL(fmi2Instantiate, "table", fmi2ModelExchange, token, resources, &cb, fmi2False, fmi2False)
#define FREE() CALL(fmi2FreeInstance, c)
#define SET_REAL(vr, value) CALL(fmi2SetReal, c, &(unsigned){vr}, 1, &(double){value})
#define GET_REAL(vr, out) CALL(fmi2GetReal, c, &(unsigned){vr}, 1, out)
#define ENTER() (CALL(fmi2SetupExperiment, c, 0, 0.0, 0.0, 0, 0.0) || CALL(fmi2EnterInitializationMode, c))
#define ENTER_ONLY() CALL(fmi2EnterInitializationMode, c)
#define EXIT() CALL(fmi2ExitInitializationMode, c)
#define UPDATE() CALL(fmi2NewDiscreteStates, c, &info)
#define ENTER_CONTINUOUS() CALL(fmi2EnterContinuousTimeMode, c)
#define ENTER_EVENT() CALL(fmi2EnterEventMode, c)
#define STEP_DONE() CALL(fmi2CompletedIntegratorStep, c, fmi2True, &flag, &flag)
#define SET_TIME(t) CALL(fmi2SetTime, c, t)
#define SET_STATES(x) CALL(fmi2SetContinuousStates, c, x, NX)
#define GET_STATES(x) CALL(fmi2GetContinuousStates, c, x, NX)
#define DERIVATIVES(dx) CALL(fmi2GetDerivatives, c, dx, NX)
#define INDICATORS(z) CALL(fmi2GetEventIndicators, c, z, NZ)
#define NOMINALS(x) CALL(fmi2GetNominalsOfContinuousStates, c, x, NX)
#define DIRECTIONAL(out) CALL(fmi2GetDirectionalDerivative, c, &vr_derivative, 1, &vr_state, 1, &(double){1.0}, out)
#define TERMINATE() CALL(fmi2Terminate, c)
#define RESET() CALL(fmi2Reset, c)
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String cat, fmi3String m) {
    if (s >= fmi3Error) errors_logged++;
}
static fmi3Boolean flag;
static fmi3Float64 next_time;
#define NEW() CALL(fmi3InstantiateModelExchange, "table", token, resources, fmi3False, fmi3False, NULL, logger)
#define FREE() CALL(fmi3FreeInstance, c)
#define SET_REAL(vr, value) CALL(fmi3SetFloat64, c, &(unsigned){vr}, 1, &(double){value}, 1)
#define GET_REAL(vr, out) CALL(fmi3GetFloat64, c, &(unsigned){vr}, 1, out, 1)
#define ENTER() CALL(fmi3EnterInitializationMode, c, fmi3False, 0.0, 0.0, fmi3False, 0.0)
#define ENTER_ONLY() ENTER()
#define EXIT() CALL(fmi3ExitInitializationMode, c)
#define UPDATE() CALL(fmi3UpdateDiscreteStates, c, &flag, &flag, &flag, &flag, &flag, &next_time)
#define ENTER_CONTINUOUS() CALL(fmi3EnterContinuousTimeMode, c)
#define ENTER_EVENT() CALL(fmi3EnterEventMode, c)
#define STEP_DONE() CALL(fmi3CompletedIntegratorStep, c, fmi3True, &flag, &flag)
#define SET_TIME(t) CALL(fmi3SetTime, c, t)
#define SET_STATES(x) CALL(fmi3SetContinuousStates, c, x, NX)
#define GET_STATES(x) CALL(fmi3GetContinuousStates, c, x, NX)
#define DERIVATIVES(dx) CALL(fmi3GetContinuousStateDerivatives, c, dx, NX)
#define INDICATORS(z) CALL(fmi3GetEventIndicators, c, z, NZ)
#define NOMINALS(x) CALL(fmi3GetNominalsOfContinuousStates, c, x, NX)
#define DIRECTIONAL(out) \
    CALL(fmi3GetDirectionalDerivative, c, &vr_derivative, 1, &vr_state, 1, &(double){1.0}, 1, out, 1)
#define ADJOINT(out) CALL(fmi3GetAdjointDerivative, c, &vr_derivative, 1, &vr_state, 1, &(double){1.0}, 1, out, 1)
#define TERMINATE() CALL(fmi3Terminate, c)
#define RESET() CALL(fmi3Reset, c)
#endif

/* Drive the fresh instance into `state`; 0 on success. A NaN input is refused with an error. */
static int reach(int state) {
    if (state == INSTANTIATED) return 0;
    if (ENTER()) return 1;
    if (state == INITIALIZATION) return 0;
    if (EXIT()) return 1;
    if (state == EVENT) return 0;
    if (state == CONTINUOUS) return UPDATE() || ENTER_CONTINUOUS();
    if (state == TERMINATED) return TERMINATE() != 0;
    return SET_REAL(vr_u, NAN) != 3;
}

/* The rest of a session from `state`, each call expected to give OK: 0, or the number of the call that did not. */
static int go_on(int state) {
    double x[NX], dx[NX], z[NZ];
    int k = 1;
    switch (state) {
    case TERMINATED: if (GET_REAL(vr_x, x)) return k; k++; /* fall through: reset, then a whole session */
    case ERROR: if (RESET()) return k; k++; /* fall through */
    case INSTANTIATED: if (ENTER()) return k; k++; /* fall through */
    case INITIALIZATION: if (EXIT()) return k; k++; /* fall through */
    case EVENT: if (UPDATE()) return k; k++; if (ENTER_CONTINUOUS()) return k; k++; /* fall through */
    case CONTINUOUS: if (SET_TIME(1e-3)) return k; k++; if (SET_STATES(STATES)) return k; k++;
                     if (DERIVATIVES(dx)) return k; k++; if (INDICATORS(z)) return k; k++;
                     if (STEP_DONE()) return k; k++; if (TERMINATE()) return k; k++;
    }
    return 0;
}

/* The function named f, in the current state, with valid arguments. */
static int call(const char *f) {
    double x[NX], z[NZ], d;
    if (IS("GetReal")) return GET_REAL(vr_x, x);
    if (IS("SetReal")) return SET_REAL(vr_u, 0.0);
    if (IS("EnterInitializationMode")) return ENTER_ONLY();
    if (IS("ExitInitializationMode")) return EXIT();
    if (IS("Terminate")) return TERMINATE();
    if (IS("Reset")) return RESET();
    if (IS("EnterEventMode")) return ENTER_EVENT();
    if (IS("NewDiscreteStates") || IS("UpdateDiscreteStates")) return UPDATE();
    if (IS("EnterContinuousTimeMode")) return ENTER_CONTINUOUS();
    if (IS("CompletedIntegratorStep")) return STEP_DONE();
    if (IS("SetTime")) return SET_TIME(0.0);
    if (IS("SetContinuousStates")) return SET_STATES(STATES);
    if (IS("GetContinuousStates")) return GET_STATES(x);
    if (IS("GetDerivatives") || IS("GetContinuousStateDerivatives")) return DERIVATIVES(x);
    if (IS("GetEventIndicators")) return INDICATORS(z);
    if (IS("GetNominalsOfContinuousStates")) return NOMINALS(x);
    if (IS("GetDirectionalDerivative")) return DIRECTIONAL(&d);
#if FMI == 3
    if (IS("GetAdjointDerivative")) return ADJOINT(&d);
#endif
    return 200; /* no such function in this host */
}

int main(int argc, char **argv) {
    /* library token resources vr_u vr_x vr_state vr_derivative; stdin: lines "function state next-state-if-ok" */
    so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    const char *token = argv[2], *resources = argv[3];
    vr_u = atoi(argv[4]), vr_x = atoi(argv[5]), vr_state = atoi(argv[6]), vr_derivative = atoi(argv[7]);
    char f[128];
    int state, next;
    while (scanf("%127s %d %d", f, &state, &next) == 3) {
        c = NEW();
        if (!c) { printf("%s %d instantiation-failed\n", f, state); continue; }
        if (reach(state)) { printf("%s %d reach-failed\n", f, state); FREE(); continue; }
        int before = errors_logged;
        int status = call(f);
        int silent = status >= 3 && errors_logged == before;
        int failed_call = go_on(status == 0 ? next : state);
        printf("%s %d status=%d%s continuation=%d\n", f, state, status, silent ? " silent" : "", failed_call);
        FREE();
    }
    return 0;
}
"""

ME_STATES = ("instantiated", "initialization", "event mode", "continuous-time mode", "terminated", "error")
EVT, CTM = 2, 3  # event mode and continuous-time mode where the co-simulation table has its step states
ME_EVERY = {INS, INI, EVT, CTM, TRM, ERR}
ME_GETS = {INI, EVT, CTM, TRM, ERR}  # from initialization mode on, and in the error state for diagnosis
ME_REST = {INS: ["EnterInitializationMode", "ExitInitializationMode", "NewDiscreteStates", "EnterContinuousTimeMode",
                 "SetTime", "SetContinuousStates", "GetDerivatives", "GetEventIndicators", "CompletedIntegratorStep",
                 "Terminate"]}
ME_REST[INI], ME_REST[EVT], ME_REST[CTM] = ME_REST[INS][1:], ME_REST[INS][2:], ME_REST[INS][4:]
ME_REST[ERR] = ["Reset"] + ME_REST[INS]
ME_REST[TRM] = ["GetReal"] + ME_REST[ERR]
# function: (the states it is allowed in, the state it leaves on OK when it changes the state). The FMI 2.0 table
# of Model Exchange (section 3.2.3; Reference-FMUs' masks in fmi2Functions.c are the same): the derivatives from
# event mode on, the nominals also when instantiated, neither in initialization mode; the states, event indicators
# and directional derivatives from initialization mode on; every get also in the error state.
FMI2_ME = {
    "EnterInitializationMode": ({INS}, INI), "ExitInitializationMode": ({INI}, EVT), "Reset": (ME_EVERY, INS),
    "Terminate": ({EVT, CTM}, TRM), "GetReal": (ME_GETS, None), "SetReal": ({INS, INI, EVT, CTM}, None),
    "EnterEventMode": ({EVT, CTM}, EVT), "NewDiscreteStates": ({EVT}, None), "EnterContinuousTimeMode": ({EVT}, CTM),
    "CompletedIntegratorStep": ({CTM}, None), "SetTime": ({EVT, CTM}, None), "SetContinuousStates": ({CTM}, None),
    "GetContinuousStates": (ME_GETS, None), "GetEventIndicators": (ME_GETS, None),
    "GetDerivatives": ({EVT, CTM, TRM, ERR}, None), "GetNominalsOfContinuousStates": ({INS, EVT, CTM, TRM, ERR}, None),
    "GetDirectionalDerivative": (ME_GETS, None),
}
# FMI 3.0 section 2.3 (the common states): the states' derivatives, the states, the event indicators, their nominals
# and the directional and adjoint derivatives in Initialization Mode, Event Mode, Continuous-Time Mode and in
# Terminated, which an FMU enters after an error (so in our error state too); the nominals not when instantiated.
# Event and continuous-time mode's own functions as in FMI 2.0, but fmi3EnterEventMode: from Continuous-Time Mode only
# (FMI 3.0's Event Mode section does not list it; Reference-FMUs' mask is Continuous-Time Mode and, with event mode
# used, co-simulation's Step Mode).
FMI3_ME = {
    "EnterInitializationMode": ({INS}, INI), "ExitInitializationMode": ({INI}, EVT), "Reset": (ME_EVERY, INS),
    "Terminate": ({EVT, CTM}, TRM), "GetReal": (ME_GETS, None), "UpdateDiscreteStates": ({EVT}, None),
    "EnterEventMode": ({CTM}, EVT), "EnterContinuousTimeMode": ({EVT}, CTM), "CompletedIntegratorStep": ({CTM}, None),
    "SetContinuousStates": ({CTM}, None),
    **{f: (ME_GETS, None) for f in ("GetContinuousStates", "GetEventIndicators", "GetContinuousStateDerivatives",
                                    "GetNominalsOfContinuousStates", "GetDirectionalDerivative",
                                    "GetAdjointDerivative")},
}


@pytest.fixture(scope="module")
def me_table_hosts(tmp_path_factory):
    return compile_hosts(ME_HOST, tmp_path_factory.mktemp("me_states"))


@pytest.mark.parametrize("version", [2, 3])
def test_a_model_exchange_instance_follows_the_standards_table(me_table_hosts, native, version, tmp_path):
    """The native CranePlant as a Model Exchange instance: each (function, state) pair gives OK where the table
    allows it, else an error with a message, and the instance goes on from the state the call left it in."""
    fmu = native[version] / "CranePlant.fmu"
    md, library, token, resources = unpack_fmu(fmu, tmp_path)
    table = FMI3_ME if version == 3 else FMI2_ME
    vr = {v.name: v.valueReference for v in md.modelVariables}
    derivative = md.derivatives[3].variable  # der(dtheta1), by theta1 (both FMI versions' value references)
    cases = [(f, s) for f in table for s in range(6)]
    stdin = "".join(f"{f} {s} {table[f][1] if table[f][1] is not None else s}\n" for f, s in cases)
    proc = subprocess.run([str(me_table_hosts[version]), library, token, resources, str(vr["u"]), str(vr["x"]),
                           str(vr["theta1"]), str(derivative.valueReference)], input=stdin, capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert len(lines) == len(cases), proc.stdout[-2000:]
    prefix, wrong = f"fmi{version}", []
    for (f, s), line in zip(cases, lines):
        expected = 0 if s in table[f][0] else 3
        if line != f"{f} {s} status={expected} continuation=0":
            got = line.split(" ", 2)[2]
            status, _, failed = got.rpartition(" continuation=")
            start = s if status != "status=0" or table[f][1] is None else table[f][1]
            then = (f", then from {ME_STATES[start]} {prefix}{ME_REST[start][int(failed) - 1]} failed"
                    if failed.isdigit() and int(failed) > 0 else "")
            wrong.append(f"{prefix}{f} when {ME_STATES[s]}: expected status {expected}, got {status}{then}")
    assert not wrong, "\n".join(wrong)
