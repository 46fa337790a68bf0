/*
 * The FMI 3.0 functions, one row each: X(return type, name, parameters, arguments), like
 * fmi2_calls.h: the loader forwards every row, the framework (fmi3Functions.c) implements the first list and
 * FMI3_MODEL_EXCHANGE, and answers FMI3_OTHERS with fmi3Error. Checked against the official fmi3Functions.h by
 * the compiler.
 * fmi3GetVersion, the three fmi3Instantiate* and fmi3FreeInstance are written out.
 */
#define VRS_ fmi3Instance c, const fmi3ValueReference vr[], size_t nvr
#define GET_(X, Type) X(fmi3Status, fmi3Get##Type, (VRS_, fmi3##Type v[], size_t n), (c, vr, nvr, v, n))
#define SET_(X, Type) X(fmi3Status, fmi3Set##Type, (VRS_, const fmi3##Type v[], size_t n), (c, vr, nvr, v, n))

#define FMI3_IMPLEMENTED(X)                                                                                  \
    X(fmi3Status, fmi3SetDebugLogging, (fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[]),  \
      (c, on, n, cats))                                                                                      \
    X(fmi3Status, fmi3EnterInitializationMode, (fmi3Instance c, fmi3Boolean tolerance_defined,               \
      fmi3Float64 tolerance, fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop),                 \
      (c, tolerance_defined, tolerance, start, stop_defined, stop))                                          \
    X(fmi3Status, fmi3ExitInitializationMode, (fmi3Instance c), (c))                                         \
    X(fmi3Status, fmi3Terminate, (fmi3Instance c), (c))                                                      \
    X(fmi3Status, fmi3Reset, (fmi3Instance c), (c))                                                          \
    GET_(X, Float64) GET_(X, Int32) GET_(X, Int64) GET_(X, UInt64) GET_(X, Boolean) GET_(X, String)                            \
    GET_(X, Float32) GET_(X, Int8) GET_(X, UInt8) GET_(X, Int16) GET_(X, UInt16) GET_(X, UInt32)                               \
    SET_(X, Float64) SET_(X, Int32) SET_(X, Int64) SET_(X, UInt64) SET_(X, Boolean) SET_(X, String)                            \
    SET_(X, Float32) SET_(X, Int8) SET_(X, UInt8) SET_(X, Int16) SET_(X, UInt16) SET_(X, UInt32)                               \
    X(fmi3Status, fmi3GetFMUState, (fmi3Instance c, fmi3FMUState *s), (c, s))                                \
    X(fmi3Status, fmi3SetFMUState, (fmi3Instance c, fmi3FMUState s), (c, s))                                 \
    X(fmi3Status, fmi3FreeFMUState, (fmi3Instance c, fmi3FMUState *s), (c, s))                               \
    X(fmi3Status, fmi3SerializedFMUStateSize, (fmi3Instance c, fmi3FMUState s, size_t *size), (c, s, size))  \
    X(fmi3Status, fmi3SerializeFMUState, (fmi3Instance c, fmi3FMUState s, fmi3Byte out[], size_t size),      \
      (c, s, out, size))                                                                                     \
    X(fmi3Status, fmi3DeserializeFMUState, (fmi3Instance c, const fmi3Byte data[], size_t size,              \
      fmi3FMUState *s), (c, data, size, s))                                                                  \
    X(fmi3Status, fmi3DoStep, (fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,           \
      fmi3Boolean *event_needed, fmi3Boolean *terminate, fmi3Boolean *early_return, fmi3Float64 *last_time),  \
      (c, t, h, no_prior, event_needed, terminate, early_return, last_time))

/* Model Exchange and the directional and adjoint derivatives: the framework implements them for a model that
   has a ContinuousModel (model.h) and refuses them otherwise. */
#define FMI3_MODEL_EXCHANGE(X)                                                                               \
    X(fmi3Status, fmi3EnterEventMode, (fmi3Instance c), (c))                                                 \
    X(fmi3Status, fmi3GetDirectionalDerivative, (fmi3Instance c, const fmi3ValueReference unknowns[],        \
      size_t nu, const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[], size_t ns,          \
      fmi3Float64 sensitivity[], size_t nsens), (c, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)) \
    X(fmi3Status, fmi3GetAdjointDerivative, (fmi3Instance c, const fmi3ValueReference unknowns[],            \
      size_t nu, const fmi3ValueReference knowns[], size_t nk, const fmi3Float64 seed[], size_t ns,          \
      fmi3Float64 sensitivity[], size_t nsens), (c, unknowns, nu, knowns, nk, seed, ns, sensitivity, nsens)) \
    X(fmi3Status, fmi3UpdateDiscreteStates, (fmi3Instance c, fmi3Boolean *update, fmi3Boolean *terminate,    \
      fmi3Boolean *nominals_changed, fmi3Boolean *values_changed, fmi3Boolean *next_defined,                 \
      fmi3Float64 *next_time), (c, update, terminate, nominals_changed, values_changed, next_defined,        \
      next_time))                                                                                            \
    X(fmi3Status, fmi3EnterContinuousTimeMode, (fmi3Instance c), (c))                                        \
    X(fmi3Status, fmi3CompletedIntegratorStep, (fmi3Instance c, fmi3Boolean no_prior, fmi3Boolean *event,    \
      fmi3Boolean *terminate), (c, no_prior, event, terminate))                                              \
    X(fmi3Status, fmi3SetTime, (fmi3Instance c, fmi3Float64 time), (c, time))                                \
    X(fmi3Status, fmi3SetContinuousStates, (fmi3Instance c, const fmi3Float64 x[], size_t n), (c, x, n))     \
    X(fmi3Status, fmi3GetContinuousStateDerivatives, (fmi3Instance c, fmi3Float64 dx[], size_t n), (c, dx, n))\
    X(fmi3Status, fmi3GetEventIndicators, (fmi3Instance c, fmi3Float64 z[], size_t n), (c, z, n))            \
    X(fmi3Status, fmi3GetContinuousStates, (fmi3Instance c, fmi3Float64 x[], size_t n), (c, x, n))           \
    X(fmi3Status, fmi3GetNominalsOfContinuousStates, (fmi3Instance c, fmi3Float64 x[], size_t n), (c, x, n)) \
    X(fmi3Status, fmi3GetNumberOfEventIndicators, (fmi3Instance c, size_t *n), (c, n))                       \
    X(fmi3Status, fmi3GetNumberOfContinuousStates, (fmi3Instance c, size_t *n), (c, n))

#define FMI3_OTHERS(X)                                                                                       \
    X(fmi3Status, fmi3GetBinary, (VRS_, size_t sizes[], fmi3Binary v[], size_t n), (c, vr, nvr, sizes, v, n)) \
    X(fmi3Status, fmi3SetBinary, (VRS_, const size_t sizes[], const fmi3Binary v[], size_t n),                \
      (c, vr, nvr, sizes, v, n))                                                                             \
    X(fmi3Status, fmi3GetClock, (VRS_, fmi3Clock v[]), (c, vr, nvr, v))                                      \
    X(fmi3Status, fmi3SetClock, (VRS_, const fmi3Clock v[]), (c, vr, nvr, v))                                \
    X(fmi3Status, fmi3GetNumberOfVariableDependencies, (fmi3Instance c, fmi3ValueReference vr, size_t *n),   \
      (c, vr, n))                                                                                            \
    X(fmi3Status, fmi3GetVariableDependencies, (fmi3Instance c, fmi3ValueReference dependent,                \
      size_t element_indices[], fmi3ValueReference independents[], size_t independent_indices[],             \
      fmi3DependencyKind kinds[], size_t n), (c, dependent, element_indices, independents,                   \
      independent_indices, kinds, n))                                                                        \
    X(fmi3Status, fmi3EnterConfigurationMode, (fmi3Instance c), (c))                                         \
    X(fmi3Status, fmi3ExitConfigurationMode, (fmi3Instance c), (c))                                          \
    X(fmi3Status, fmi3GetIntervalDecimal, (VRS_, fmi3Float64 intervals[], fmi3IntervalQualifier q[]),        \
      (c, vr, nvr, intervals, q))                                                                            \
    X(fmi3Status, fmi3GetIntervalFraction, (VRS_, fmi3UInt64 counters[], fmi3UInt64 resolutions[],           \
      fmi3IntervalQualifier q[]), (c, vr, nvr, counters, resolutions, q))                                    \
    X(fmi3Status, fmi3GetShiftDecimal, (VRS_, fmi3Float64 shifts[]), (c, vr, nvr, shifts))                   \
    X(fmi3Status, fmi3GetShiftFraction, (VRS_, fmi3UInt64 counters[], fmi3UInt64 resolutions[]),             \
      (c, vr, nvr, counters, resolutions))                                                                   \
    X(fmi3Status, fmi3SetIntervalDecimal, (VRS_, const fmi3Float64 intervals[]), (c, vr, nvr, intervals))    \
    X(fmi3Status, fmi3SetIntervalFraction, (VRS_, const fmi3UInt64 counters[], const fmi3UInt64 res[]),      \
      (c, vr, nvr, counters, res))                                                                           \
    X(fmi3Status, fmi3SetShiftDecimal, (VRS_, const fmi3Float64 shifts[]), (c, vr, nvr, shifts))             \
    X(fmi3Status, fmi3SetShiftFraction, (VRS_, const fmi3UInt64 counters[], const fmi3UInt64 res[]),         \
      (c, vr, nvr, counters, res))                                                                           \
    X(fmi3Status, fmi3EvaluateDiscreteStates, (fmi3Instance c), (c))                                         \
    X(fmi3Status, fmi3EnterStepMode, (fmi3Instance c), (c))                                                  \
    X(fmi3Status, fmi3GetOutputDerivatives, (VRS_, const fmi3Int32 orders[], fmi3Float64 v[], size_t n),     \
      (c, vr, nvr, orders, v, n))                                                                            \
    X(fmi3Status, fmi3ActivateModelPartition, (fmi3Instance c, fmi3ValueReference clock, fmi3Float64 time),  \
      (c, clock, time))

#define FMI3_UNSUPPORTED(X) FMI3_OTHERS(X) FMI3_MODEL_EXCHANGE(X) /* what the Python FMUs' loader forwards */
