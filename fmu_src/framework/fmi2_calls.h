/*
 * The FMI 2.0 functions, one row each: X(return type, name, parameters, arguments). Shared by the Python FMUs'
 * loader (python/fmi2_loader.c, which forwards every row) and the framework (fmi2Functions.c, which implements
 * the first list and FMI2_DERIVATIVES, and answers FMI2_OTHERS with fmi2Error; its Model Exchange functions,
 * which the co-simulation-only Python FMUs do not export, are written out there). Both include the official
 * fmi2Functions.h, so the compiler checks every row against the standard's prototypes.
 * The first parameter is always `c`.
 * fmi2GetTypesPlatform, fmi2GetVersion, fmi2Instantiate and fmi2FreeInstance are written out.
 */
#define FMI2_IMPLEMENTED(X)                                                                                  \
    X(fmi2Status, fmi2SetDebugLogging, (fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]), \
      (c, on, n, cats))                                                                                      \
    X(fmi2Status, fmi2SetupExperiment, (fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance,  \
      fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop), (c, tolerance_defined, tolerance, start,      \
      stop_defined, stop))                                                                                   \
    X(fmi2Status, fmi2EnterInitializationMode, (fmi2Component c), (c))                                       \
    X(fmi2Status, fmi2ExitInitializationMode, (fmi2Component c), (c))                                        \
    X(fmi2Status, fmi2Terminate, (fmi2Component c), (c))                                                     \
    X(fmi2Status, fmi2Reset, (fmi2Component c), (c))                                                         \
    X(fmi2Status, fmi2GetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]),    \
      (c, vr, n, v))                                                                                         \
    X(fmi2Status, fmi2GetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                \
      fmi2Integer v[]), (c, vr, n, v))                                                                       \
    X(fmi2Status, fmi2GetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                \
      fmi2Boolean v[]), (c, vr, n, v))                                                                       \
    X(fmi2Status, fmi2GetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]),\
      (c, vr, n, v))                                                                                         \
    X(fmi2Status, fmi2SetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                   \
      const fmi2Real v[]), (c, vr, n, v))                                                                    \
    X(fmi2Status, fmi2SetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                \
      const fmi2Integer v[]), (c, vr, n, v))                                                                 \
    X(fmi2Status, fmi2SetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                \
      const fmi2Boolean v[]), (c, vr, n, v))                                                                 \
    X(fmi2Status, fmi2SetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n,                 \
      const fmi2String v[]), (c, vr, n, v))                                                                  \
    X(fmi2Status, fmi2GetFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))                               \
    X(fmi2Status, fmi2SetFMUstate, (fmi2Component c, fmi2FMUstate s), (c, s))                                \
    X(fmi2Status, fmi2FreeFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))                             \
    X(fmi2Status, fmi2SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *size), (c, s, size)) \
    X(fmi2Status, fmi2SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte out[], size_t size),     \
      (c, s, out, size))                                                                                     \
    X(fmi2Status, fmi2DeSerializeFMUstate, (fmi2Component c, const fmi2Byte data[], size_t size,             \
      fmi2FMUstate *s), (c, data, size, s))                                                                  \
    X(fmi2Status, fmi2DoStep, (fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior),               \
      (c, t, h, no_prior))                                                                                   \
    X(fmi2Status, fmi2GetRealStatus, (fmi2Component c, const fmi2StatusKind kind, fmi2Real *v), (c, kind, v))\
    X(fmi2Status, fmi2GetBooleanStatus, (fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *v),        \
      (c, kind, v))

/* The directional derivatives: the framework implements them for a model that has a ContinuousModel (model.h)
   and refuses them otherwise. */
#define FMI2_DERIVATIVES(X)                                                                                  \
    X(fmi2Status, fmi2GetDirectionalDerivative, (fmi2Component c, const fmi2ValueReference u[], size_t nu,   \
      const fmi2ValueReference z[], size_t nz, const fmi2Real dv[], fmi2Real dz[]), (c, u, nu, z, nz, dv, dz))

#define FMI2_OTHERS(X)                                                                                       \
    X(fmi2Status, fmi2SetRealInputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,    \
      const fmi2Integer order[], const fmi2Real v[]), (c, vr, n, order, v))                                  \
    X(fmi2Status, fmi2GetRealOutputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,   \
      const fmi2Integer order[], fmi2Real v[]), (c, vr, n, order, v))                                        \
    X(fmi2Status, fmi2CancelStep, (fmi2Component c), (c))                                                    \
    X(fmi2Status, fmi2GetStatus, (fmi2Component c, const fmi2StatusKind kind, fmi2Status *v), (c, kind, v))  \
    X(fmi2Status, fmi2GetIntegerStatus, (fmi2Component c, const fmi2StatusKind kind, fmi2Integer *v),        \
      (c, kind, v))                                                                                          \
    X(fmi2Status, fmi2GetStringStatus, (fmi2Component c, const fmi2StatusKind kind, fmi2String *v),          \
      (c, kind, v))

#define FMI2_UNSUPPORTED(X) FMI2_OTHERS(X) FMI2_DERIVATIVES(X) /* what the Python FMUs' loader forwards */
