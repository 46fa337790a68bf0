/*
 * A system of native components as one model (system.c): what its generated system_config.h describes. Each
 * instance's model is reached through its ModelType (model.h), <ModelIdentifier>_MODEL of its model file.
 */
#ifndef SYSTEM_H
#define SYSTEM_H

#include "model.h"

/* One instance of a component model, and the system's data for it. */
typedef struct {
    const char *name; /* the instance's name: its messages are prefixed with it */
    const ModelType *type;
    unsigned n_outputs; /* every output, read into the buffer from `buffer` on */
    const unsigned *outputs;
    unsigned buffer;
    unsigned n_inputs; /* the connected inputs and the buffer positions that feed them */
    const unsigned *inputs, *sources;
    unsigned n_reals; /* the system's parameter values, set after the start values */
    const unsigned *real_vrs;
    const double *reals;
    unsigned n_strings;
    const unsigned *string_vrs;
    const char *const *strings;
    unsigned n_integers; /* Enumerations, by their items' values */
    const unsigned *integer_vrs;
    const long long *integers;
} InstanceRow;

/* The exchange in Gauss-Seidel order (crane_fmu.cosim.master.Wiring.propagation): read an instance's outputs
   or set its connected inputs. */
typedef enum { READ, WRITE } Operation;
typedef struct {
    Operation operation;
    unsigned instance;
} Exchange;

/* Where a variable of the system goes: a parameter or input to an instance's variable, an output from a
   buffer position. */
typedef struct {
    unsigned vr, instance, target;
} Link;

#endif
