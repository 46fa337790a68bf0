/*
 * The loaders' search for a CPython (3.10 or newer) to run the FMU's wrapper, with no Python
 * dependency of its own. Places tried, in order, until one gives a usable libpython:
 *   1. the host process: a Python host (fmpy, ...) already has one, and no second may be loaded;
 *   2. CRANE_FMU_PYTHON: a libpython file, or a Python executable that is asked for its libpython;
 *   3. the libpython recorded when the FMU was built (LIBPYTHON);
 *   4. the dynamic linker's search (LD_LIBRARY_PATH, ld.so.cache, system folders) for its soname;
 *   5. the same search for the other CPythons' sonames (FALLBACK_SONAMES, newest first);
 *   6. python3, then python, on PATH, asked for their libpython.
 * A CRANE_FMU_PYTHON that cannot be used ends the search with the reason: the FMU never quietly
 * takes another Python than the one its user named.
 * The chosen libpython is loaded with RTLD_GLOBAL and told where its standard library is (its home,
 * found beside the library), so that it does not take its paths from whatever python3 comes first
 * on PATH; then the wrapper (built against Python's limited API, so any CPython from 3.10 on will
 * do) next to the loader is loaded. Thread-safe: one search at a time.
 */
#define _GNU_SOURCE /* dladdr, RTLD_DEFAULT */
#include <dlfcn.h>
#include <limits.h>
#include <libgen.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <wchar.h>

/* For Python hosts: every FMI call of this FMU runs Python in the host's own interpreter (place 1
   above) under its GIL, so a host may call it without releasing the GIL first (ctypes.PyDLL, not
   ctypes.CDLL) and save a release and re-acquire per call. The master of crane_fmu.cosim does. */
__attribute__((visibility("default"))) const int crane_fmu_runs_in_host_python = 1;

#ifndef FALLBACK_SONAMES
#define FALLBACK_SONAMES "libpython3.13.so.1.0:libpython3.12.so.1.0:libpython3.11.so.1.0:libpython3.10.so.1.0"
#endif
#define PYTHON_VARIABLE "CRANE_FMU_PYTHON"
#define ASK_LIBPYTHON                                                                                        \
    " -c 'import os, sysconfig as s; print(os.path.join(s.get_config_var(\"LIBDIR\") or \"\","               \
    " s.get_config_var(\"INSTSONAME\") or \"\"))' 2>/dev/null"

typedef struct {
    char text[8192]; /* "place (why not); place (why not); ..." */
    size_t used;
} Tried;

static void note(Tried *t, const char *format, ...) {
    if (t->used + 3 >= sizeof t->text) return;
    if (t->used) t->used += (size_t)snprintf(t->text + t->used, sizeof t->text - t->used, "; ");
    va_list args;
    va_start(args, format);
    int n = vsnprintf(t->text + t->used, sizeof t->text - t->used, format, args);
    va_end(args);
    if (n > 0) t->used = t->used + (size_t)n < sizeof t->text ? t->used + (size_t)n : sizeof t->text - 1;
}

/* "3.12.1" from the library's Py_GetVersion() into `version`; 1 if it is CPython 3.10 or newer. */
static int recent_enough(void *lib, char *version, size_t size) {
    const char *(*get_version)(void) = (const char *(*)(void))dlsym(lib, "Py_GetVersion");
    int major = 0, minor = 0;
    snprintf(version, size, "%s", get_version ? get_version() : "unknown");
    version[strcspn(version, " ")] = 0;
    return sscanf(version, "%d.%d", &major, &minor) == 2 && major == 3 && minor >= 10;
}

/* dlopen `path` with its symbols global if it is a recent enough libpython; else note why not. */
static void *try_library(const char *path, const char *place, Tried *t, char *version, size_t size) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_GLOBAL);
    if (!lib) {
        note(t, "%s (%s)", place, dlerror());
        return NULL;
    }
    if (!recent_enough(lib, version, size)) {
        note(t, "%s (%s is CPython %s, older than 3.10)", place, path, version);
        dlclose(lib);
        return NULL;
    }
    return lib;
}

/* The libpython of the Python executable `exe` (run once with ASK_LIBPYTHON). */
static void *try_executable(const char *exe, const char *place, Tried *t, char *version, size_t size,
                            char *found, size_t found_size) {
    char command[4400] = "'";
    size_t n = 1;
    for (const char *p = exe; *p && n + 8 < 4096; p++) { /* single-quoted for the shell */
        if (*p == '\'') n += (size_t)snprintf(command + n, sizeof command - n, "'\\''");
        else command[n++] = *p;
    }
    snprintf(command + n, sizeof command - n, "'%s", ASK_LIBPYTHON);
    FILE *pipe = popen(command, "r");
    char line[4096] = {0};
    if (!pipe || !fgets(line, sizeof line, pipe)) line[0] = 0;
    if (pipe) pclose(pipe);
    line[strcspn(line, "\r\n")] = 0;
    if (!line[0] || line[strlen(line) - 1] == '/') {
        note(t, "%s (%s did not run, or named no shared libpython)", place, exe);
        return NULL;
    }
    snprintf(found, found_size, "%s", line);
    return try_library(line, place, t, version, size);
}

/* The host process's own Python (`symbol` is its Py_IsInitialized), its symbols made global; NULL if
   it is older than 3.10. */
static void *host_python(void *symbol, Tried *t, char *version, size_t size, char *found, size_t found_size) {
    Dl_info info;
    void *lib = NULL;
    if (dladdr(symbol, &info) && info.dli_fname) {
        snprintf(found, found_size, "%s", info.dli_fname);
        lib = dlopen(info.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
    }
    if (!lib) lib = dlopen(NULL, RTLD_NOW); /* the symbols are the executable's own */
    if (!recent_enough(lib, version, size)) {
        note(t, "the host process (its Python is %s, older than 3.10)", version);
        return NULL;
    }
    return lib;
}

/* The home of the libpython `lib`, CPython `version`: the first folder at or above the library's
   own that holds lib/python3.X/os.py (or lib64/...), the prefix its standard library is under.
   0 if there is none. */
static int python_home(void *lib, const char *version, char *home, size_t size) {
    Dl_info info;
    char real[PATH_MAX], landmark[PATH_MAX + 64];
    int major = 0, minor = 0;
    void *symbol = dlsym(lib, "Py_GetVersion");
    if (!symbol || !dladdr(symbol, &info) || !info.dli_fname || !realpath(info.dli_fname, real) ||
        sscanf(version, "%d.%d", &major, &minor) != 2)
        return 0;
    for (char *slash = strrchr(real, '/'); slash; slash = strrchr(real, '/')) {
        *slash = 0; /* real: the library's folder, then each folder above it ("" for /) */
        for (int lib64 = 0; lib64 < 2; lib64++) {
            snprintf(landmark, sizeof landmark, "%s/%s/python%d.%d/os.py", real, lib64 ? "lib64" : "lib", major,
                     minor);
            if (access(landmark, R_OK) == 0) {
                snprintf(home, size, "%s", real[0] ? real : "/");
                return 1;
            }
        }
    }
    return 0;
}

/* Before the interpreter starts: tell the libpython `lib` its home (see python_home), unless the
   user set PYTHONHOME. Adds to `used` what was done. */
static void set_python_home(void *lib, const char *version, char *used, size_t used_size) {
    static wchar_t home_wide[PATH_MAX]; /* Py_SetPythonHome keeps the pointer */
    char home[PATH_MAX];
    size_t n = strlen(used);
    void (*set_home)(const wchar_t *) = (void (*)(const wchar_t *))dlsym(lib, "Py_SetPythonHome");
    if (getenv("PYTHONHOME")) {
        snprintf(used + n, used_size - n, ", its home from PYTHONHOME=%s", getenv("PYTHONHOME"));
    } else if (!set_home || !python_home(lib, version, home, sizeof home) ||
               mbstowcs(home_wide, home, PATH_MAX) >= PATH_MAX) {
        snprintf(used + n, used_size - n, ", no standard library found beside it: CPython looks for its own");
    } else {
        set_home(home_wide);
        snprintf(used + n, used_size - n, ", its home %s", home);
    }
}

/* Find a libpython (see the top of this file). Returns 1 and says in `used` which one and how it
   was found; 0 after listing in `tried` every place tried; -1 if CRANE_FMU_PYTHON is set but
   unusable (the reason in `tried`). */
static int find_python(Tried *tried, char *used, size_t used_size) {
    char version[64] = "", path[4096] = "", place[4300];
    void *host = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (host) { /* a Python host: its own interpreter or none, never a second one */
        if (!host_python(host, tried, version, sizeof version, path, sizeof path)) return 0;
        snprintf(used, used_size, "using the host process's CPython %s (%s)%s", version, path,
                 getenv(PYTHON_VARIABLE) ? "; " PYTHON_VARIABLE " does not apply in a Python host" : "");
        return 1;
    }
    void *lib = NULL;
    const char *variable = getenv(PYTHON_VARIABLE);
    if (variable && *variable) { /* the user's choice, or none: `tried` then says only why not */
        const char *file = strrchr(variable, '/') ? strrchr(variable, '/') + 1 : variable;
        snprintf(place, sizeof place, "%s=%s", PYTHON_VARIABLE, variable);
        snprintf(path, sizeof path, "%s", variable);
        lib = strstr(file, "libpython") ? try_library(variable, place, tried, version, sizeof version)
                                        : try_executable(variable, place, tried, version, sizeof version, path,
                                                         sizeof path);
        if (!lib) return -1;
    } else {
        note(tried, "the host process (no Python in it)");
        note(tried, "%s (not set)", PYTHON_VARIABLE);
    }
    if (!lib) {
        snprintf(place, sizeof place, "the libpython recorded at build time, %s", LIBPYTHON);
        snprintf(path, sizeof path, "%s", LIBPYTHON);
        lib = try_library(LIBPYTHON, place, tried, version, sizeof version);
    }
    char sonames[1024];
    snprintf(sonames, sizeof sonames, "%s:%s", LIBPYTHON_SONAME, FALLBACK_SONAMES);
    for (char *save = NULL, *soname = strtok_r(sonames, ":", &save); !lib && soname;
         soname = strtok_r(NULL, ":", &save)) {
        snprintf(place, sizeof place, "the dynamic linker's search for %s", soname);
        snprintf(path, sizeof path, "%s", soname);
        lib = try_library(soname, place, tried, version, sizeof version);
    }
    static const char *const on_path[] = {"python3", "python"};
    for (int i = 0; !lib && i < 2; i++) {
        snprintf(place, sizeof place, "%s on PATH", on_path[i]);
        lib = try_executable(on_path[i], place, tried, version, sizeof version, path, sizeof path);
    }
    if (!lib) return 0;
    snprintf(used, used_size, "using CPython %s from %s (found by: %s)", version, path, place);
    set_python_home(lib, version, used, used_size);
    return 1;
}

/* Find a Python and load the wrapper next to this loader (once; a failed search is repeated on the
   next call). Returns the wrapper's handle, or NULL with the reason in `message`; `used` says which
   Python was taken. */
static void *load_wrapper(const char *function, char *message, size_t size, char *used, size_t used_size) {
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    static void *wrapper;
    static char found[4400];
    pthread_mutex_lock(&lock);
    if (!wrapper) {
        Tried *tried = calloc(1, sizeof *tried);
        int status = 0;
        if (!tried) {
            snprintf(message, size, "%s: out of memory", function);
        } else if ((status = find_python(tried, found, sizeof found)) < 0) {
            snprintf(message, size,
                     "%s: the CPython named by %s cannot be used: %s. Set it to a CPython 3.10 or newer (an "
                     "executable, or its shared libpython), or unset it to let the FMU search for one",
                     function, PYTHON_VARIABLE, tried->text);
        } else if (!status) {
            snprintf(message, size,
                     "%s: found no CPython 3.10 or newer (with a shared libpython) to run this FMU's Python model. "
                     "Tried: %s. Set %s to a Python executable (e.g. /usr/bin/python3) or to its libpython "
                     "(e.g. /usr/lib/x86_64-linux-gnu/libpython3.11.so.1.0)",
                     function, tried->text, PYTHON_VARIABLE);
        } else {
            Dl_info self;
            char path[4096], file[4200];
            dladdr((void *)&load_wrapper, &self);
            snprintf(path, sizeof path, "%s", self.dli_fname);
            snprintf(file, sizeof file, "%s/PythonWrapper.so", dirname(path));
            wrapper = dlopen(file, RTLD_NOW | RTLD_LOCAL);
            if (!wrapper) snprintf(message, size, "%s: cannot load %s (%s): %s", function, file, found, dlerror());
        }
        free(tried);
    }
    snprintf(used, used_size, "%s", found);
    pthread_mutex_unlock(&lock);
    return wrapper;
}
