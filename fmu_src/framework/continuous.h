/*
 * What the FMI 2.0 and 3.0 frameworks share for Model Exchange (model.h's ContinuousModel): the modes of a host
 * that integrates the model (event mode, continuous-time mode; FMI 2.0 section 3.2.3, FMI 3.0 section 3.2), the
 * continuous states, derivatives and event indicators with their argument checks, and the directional and
 * adjoint derivatives. Each call checks the mode first, as instance.c's do.
 */
#ifndef CONTINUOUS_H
#define CONTINUOUS_H

#include <stddef.h>

#include "instance.h"

/* Is `c` an instance the host integrates? If not, it logs why. */
int is_model_exchange(Instance *c, const char *function);
int set_time(Instance *c, const char *function, double time);
/* Event mode from the `modes` the version allows: FMI 2.0 also from event mode, FMI 3.0 from continuous-time
   mode only (its Event Mode section does not list fmi3EnterEventMode). */
int enter_event_mode(Instance *c, const char *function, int modes);
int enter_continuous_time_mode(Instance *c, const char *function);
/* The model needs no event at an integrator step (its events are all state events). */
int completed_integrator_step(Instance *c, const char *function, int *enter_event_mode, int *terminate);
/* One event update; the model's discrete state is settled after it (no further update needed). */
int update_discrete_states(Instance *c, const char *function, int *terminate, int *states_changed);
int get_continuous_states(Instance *c, const char *function, double x[], size_t n);
int set_continuous_states(Instance *c, const char *function, const double x[], size_t n);
/* The derivatives and the nominals in `modes` (FMI 2.0 and 3.0 differ: each version's file says). */
int get_derivatives(Instance *c, const char *function, int modes, double dx[], size_t n);
int get_event_indicators(Instance *c, const char *function, double z[], size_t n);
int get_nominals(Instance *c, const char *function, int modes, double x[], size_t n);
/* The numbers of states and event indicators (0 for co-simulation). */
size_t number_of_states(const Instance *c);
size_t number_of_indicators(const Instance *c);
/* sensitivity = J seed (directional) or J^T seed (adjoint), J = d unknowns / d knowns; value references as
   get_reals'. Model Exchange and co-simulation instances alike. */
int directional_derivative(Instance *c, const char *function, const unsigned unknowns[], size_t nu,
                           const unsigned knowns[], size_t nk, const double seed[], double sensitivity[]);
int adjoint_derivative(Instance *c, const char *function, const unsigned unknowns[], size_t nu,
                       const unsigned knowns[], size_t nk, const double seed[], double sensitivity[]);

#endif
