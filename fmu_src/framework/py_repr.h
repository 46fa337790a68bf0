/* A double as Python's repr() writes it (the shortest text that reads back exactly), so that the
   native FMU's messages are the Python FMU's, e.g. "l1 must be > 0 and finite, got -1.0". */
#ifndef PY_REPR_H
#define PY_REPR_H

#include <stddef.h>

#define REPR_SIZE 32 /* enough for any double */

/* Writes repr(value) into out (REPR_SIZE bytes) and returns out. */
char *py_repr(double value, char out[REPR_SIZE]);

#endif
