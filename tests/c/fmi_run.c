/* fmi_run.c: runs the FMI 2.0 co-simulation calling sequence on one BreathingTorso binary and
 * prints one Real output at every communication point, so that two platforms' binaries of
 * the same FMU can be compared (python/tests/test_fmu_win64.py: the win64 DLL under wine
 * against the linux64 shared object).
 *
 * The same source builds on Linux (dlopen) and for Windows (LoadLibrary, with mingw-w64).
 * Types come from the official FMI 2.0 headers (fmi2FunctionTypes.h, shipped in fmpy).
 *
 * Sequence: fmi2GetVersion, fmi2GetTypesPlatform, fmi2Instantiate (loggingOn, a logger that
 * prints to stderr), fmi2SetupExperiment (no tolerance, start 0, stop STEPS * H),
 * fmi2EnterInitializationMode, fmi2SetReal of every VR=VALUE argument,
 * fmi2ExitInitializationMode, STEPS times fmi2DoStep and fmi2GetReal of OUTPUT_VR,
 * fmi2Terminate, fmi2FreeInstance.
 *
 * Usage: fmi_run LIBRARY GUID STEPS H OUTPUT_VR [VR=VALUE ...]
 * Output: "t bits value" per step, where bits is the IEEE 754 double in hexadecimal (exact,
 * whatever the C library's printf does with 17 digits). Exit status 0 when every call
 * returned fmi2OK.
 */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(Library lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static void close_library(Library lib) { FreeLibrary(lib); }
#else
#include <dlfcn.h>
typedef void *Library;
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(Library lib, const char *name) { return dlsym(lib, name); }
static void close_library(Library lib) { dlclose(lib); }
#endif

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] %s status %d: ", category, name, (int)status);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

#define CHECK(call)                                                                 \
    do {                                                                            \
        fmi2Status s_ = (call);                                                     \
        if (s_ != fmi2OK) {                                                         \
            fprintf(stderr, "fmi_run: %s returned status %d\n", #call, (int)s_);    \
            return 1;                                                               \
        }                                                                           \
    } while (0)

#define LOAD(type, var, name)                                                       \
    type *var = (type *)symbol(lib, name);                                          \
    if (!var) {                                                                     \
        fprintf(stderr, "fmi_run: %s is not exported by %s\n", name, argv[1]);      \
        return 1;                                                                   \
    }

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: fmi_run LIBRARY GUID STEPS H OUTPUT_VR [VR=VALUE ...]\n");
        return 2;
    }
    Library lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "fmi_run: cannot load %s\n", argv[1]);
        return 1;
    }
    const char *guid = argv[2];
    long steps = strtol(argv[3], NULL, 10);
    double h = strtod(argv[4], NULL);
    fmi2ValueReference output = (fmi2ValueReference)strtoul(argv[5], NULL, 10);

    LOAD(fmi2GetVersionTYPE, get_version, "fmi2GetVersion");
    LOAD(fmi2GetTypesPlatformTYPE, get_types_platform, "fmi2GetTypesPlatform");
    LOAD(fmi2InstantiateTYPE, instantiate, "fmi2Instantiate");
    LOAD(fmi2SetupExperimentTYPE, setup_experiment, "fmi2SetupExperiment");
    LOAD(fmi2EnterInitializationModeTYPE, enter_init, "fmi2EnterInitializationMode");
    LOAD(fmi2ExitInitializationModeTYPE, exit_init, "fmi2ExitInitializationMode");
    LOAD(fmi2SetRealTYPE, set_real, "fmi2SetReal");
    LOAD(fmi2GetRealTYPE, get_real, "fmi2GetReal");
    LOAD(fmi2DoStepTYPE, do_step, "fmi2DoStep");
    LOAD(fmi2TerminateTYPE, terminate, "fmi2Terminate");
    LOAD(fmi2FreeInstanceTYPE, free_instance, "fmi2FreeInstance");

    if (strcmp(get_version(), "2.0") != 0 || strcmp(get_types_platform(), "default") != 0) {
        fprintf(stderr, "fmi_run: version %s, types platform %s\n", get_version(),
                get_types_platform());
        return 1;
    }
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c =
        instantiate("fmi_run", fmi2CoSimulation, guid, NULL, &callbacks, fmi2False, fmi2True);
    if (!c) {
        fprintf(stderr, "fmi_run: fmi2Instantiate returned NULL\n");
        return 1;
    }
    CHECK(setup_experiment(c, fmi2False, 0.0, 0.0, fmi2True, (double)steps * h));
    CHECK(enter_init(c));
    for (int i = 6; i < argc; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq) {
            fprintf(stderr, "fmi_run: %s is not VR=VALUE\n", argv[i]);
            return 2;
        }
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[i], NULL, 10);
        fmi2Real value = strtod(eq + 1, NULL);
        CHECK(set_real(c, &vr, 1, &value));
    }
    CHECK(exit_init(c));
    for (long k = 0; k < steps; k++) {
        double t = (double)k * h;
        CHECK(do_step(c, t, h, fmi2True));
        fmi2Real value;
        CHECK(get_real(c, &output, 1, &value));
        uint64_t bits;
        memcpy(&bits, &value, sizeof bits);
        printf("%ld %016llx %.17g\n", k + 1, (unsigned long long)bits, value);
    }
    CHECK(terminate(c));
    free_instance(c);
    close_library(lib);
    return 0;
}
