#include "py_repr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The decimal of as many digits as sci (d.ddde[+-]x, no sign) one unit of its last digit above it (up) or below. */
static void next_decimal(const char *sci, int up, char out[REPR_SIZE]) {
    unsigned long long m = 0, limit = 1; /* the digits as a whole number, and 10^digits */
    const char *p = sci;
    for (; *p && *p != 'e'; p++)
        if (*p != '.') m = m * 10 + (unsigned)(*p - '0'), limit *= 10;
    int exponent = atoi(p + 1);
    m = up ? m + 1 : m - 1;
    if (m == limit) m /= 10, exponent++;                   /* 9.99 -> 10.0: 1.00, one more in the exponent */
    else if (m < limit / 10) m = limit - 1, exponent--;   /* 1.00 -> 0.999: 9.99, one less */
    char digits[24];
    snprintf(digits, sizeof digits, "%llu", m);
    snprintf(out, REPR_SIZE, "%c%s%se%d", digits[0], digits[1] ? "." : "", digits + 1, exponent);
}

char *py_repr(double value, char out[REPR_SIZE]) {
    if (isnan(value)) return strcpy(out, "nan");
    if (isinf(value)) return strcpy(out, value > 0 ? "inf" : "-inf");
    /* the shortest mantissa that reads back exactly, as d.ddde[+-]x: the digits rounded from the value, or
       where they miss it (beside a power of two, where the doubles' spacing halves) the next decimal of as many
       digits on the value's side, as Python's shortest repr finds it */
    char sci[REPR_SIZE], next[REPR_SIZE];
    double magnitude = fabs(value);
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(sci, sizeof sci, "%.*e", digits - 1, magnitude);
        double back = strtod(sci, NULL);
        if (back == magnitude) break;
        next_decimal(sci, back < magnitude, next);
        if (strtod(next, NULL) == magnitude) {
            strcpy(sci, next);
            break;
        }
    }
    const char *p = sci;
    int negative = signbit(value) != 0;
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
