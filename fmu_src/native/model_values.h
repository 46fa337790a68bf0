/*
 * What every model file does alike with its generated variable table (<model>_variables.h, included
 * first, with model.h and py_repr.h): check a set of Reals, all before any is stored, and store them.
 */
#ifndef MODEL_VALUES_H
#define MODEL_VALUES_H

static ModelStatus set_real_values(double store[], const unsigned vr[], size_t n, const double values[],
                                   int fixed_allowed, const Reporter *r) {
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VARIABLES)
            return report(r, MODEL_ERROR, "%s has no variable with value reference %u", MODEL_IDENTIFIER, vr[i]);
        const VariableRow *v = &VARIABLE_TABLE[vr[i]];
        if (v->type == STRING)
            return report(r, MODEL_ERROR, "%s of %s is a String, not a Real", v->name, MODEL_IDENTIFIER);
        if (v->causality == OUTPUT)
            return report(r, MODEL_ERROR, "%s is an output of %s; only parameters and inputs can be set", v->name,
                          MODEL_IDENTIFIER);
        if (v->causality == INPUT && !isfinite(values[i]))
            return report(r, MODEL_ERROR, "input %s must be finite, got %s", v->name,
                          py_repr(values[i], (char[REPR_SIZE]){0}));
        if (v->causality == PARAMETER && !fixed_allowed)
            return report(r, MODEL_ERROR, "%s is a fixed parameter of %s: it can be set only before initialisation ends",
                          v->name, MODEL_IDENTIFIER);
    }
    for (size_t i = 0; i < n; i++) store[vr[i]] = values[i];
    return MODEL_OK;
}

#endif
