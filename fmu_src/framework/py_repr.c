#include "py_repr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char *py_repr(double value, char out[REPR_SIZE]) {
    if (isnan(value)) return strcpy(out, "nan");
    if (isinf(value)) return strcpy(out, value > 0 ? "inf" : "-inf");
    /* the shortest mantissa that reads back exactly, as d.ddde[+-]x */
    char sci[REPR_SIZE];
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(sci, sizeof sci, "%.*e", digits - 1, value);
        if (strtod(sci, NULL) == value) break;
    }
    const char *p = sci;
    int negative = *p == '-';
    if (negative) p++;
    char mantissa[20];
    size_t n = 0;
    for (; *p && *p != 'e'; p++)
        if (*p != '.') mantissa[n++] = *p;
    while (n > 1 && mantissa[n - 1] == '0') n--; /* "1.50000" was asked for 6 digits: keep "15" */
    mantissa[n] = '\0';
    int exponent = atoi(p + 1);
    char *o = out;
    if (negative) *o++ = '-';
    if (exponent < -4 || exponent >= 16) { /* Python's repr switches to scientific notation there */
        *o++ = mantissa[0];
        if (n > 1) {
            *o++ = '.';
            memcpy(o, mantissa + 1, n - 1);
            o += n - 1;
        }
        int e = abs(exponent) % 1000; /* a double's exponent has at most three digits */
        snprintf(o, 8, "e%c%02d", exponent < 0 ? '-' : '+', e);
    } else if (exponent < 0) { /* 0.000ddd */
        o += sprintf(o, "0.");
        for (int i = 0; i < -exponent - 1; i++) *o++ = '0';
        memcpy(o, mantissa, n + 1);
    } else { /* ddd.ddd, at least one digit after the point */
        for (int i = 0; i <= exponent; i++) *o++ = (size_t)i < n ? mantissa[i] : '0';
        *o++ = '.';
        if ((size_t)exponent + 1 < n) memcpy(o, mantissa + exponent + 1, n - (size_t)exponent);
        else strcpy(o, "0");
    }
    return out;
}
