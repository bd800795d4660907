/* fmi3_run.c: runs the FMI 3.0 co-simulation calling sequence on one BreathingTorso binary and
 * prints one Float64 output at every communication point, so that two platforms' binaries of
 * the same FMU can be compared (python/tests/test_fmu_win64.py: the win64 DLL of
 * fmu/BreathingTorso3.fmu under wine against its linux64 shared object). The FMI 2.0
 * counterpart is fmi_run.c.
 *
 * The same source builds on Linux (dlopen) and for Windows (LoadLibrary, with mingw-w64).
 * Types come from the official FMI 3.0 headers (fmi3FunctionTypes.h, shipped in fmpy).
 *
 * Sequence: fmi3GetVersion, fmi3InstantiateCoSimulation (loggingOn, no event mode, no early
 * return, no intermediate variables, a logger that prints to stderr, no intermediate-update
 * callback), fmi3EnterInitializationMode (no tolerance, start 0, stop STEPS * H),
 * fmi3SetFloat64 of every VR=VALUE argument, fmi3ExitInitializationMode, STEPS times
 * fmi3DoStep (which must neither ask for event handling, nor terminate, nor return early, and
 * must reach t + H) and fmi3GetFloat64 of OUTPUT_VR, fmi3Terminate, fmi3FreeInstance.
 *
 * Usage: fmi3_run LIBRARY TOKEN RESOURCE_PATH STEPS H OUTPUT_VR [VR=VALUE ...]
 *        (RESOURCE_PATH "-" passes NULL)
 * Output: "step bits value" per step, where bits is the IEEE 754 double in hexadecimal
 * (exact, whatever the C library's printf does with 17 digits). Exit status 0 when every call
 * returned fmi3OK.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3FunctionTypes.h"

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

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message) {
    (void)env;
    fprintf(stderr, "[%s] status %d: %s\n", category, (int)status, message);
}

#define CHECK(call)                                                                 \
    do {                                                                            \
        fmi3Status s_ = (call);                                                     \
        if (s_ != fmi3OK) {                                                         \
            fprintf(stderr, "fmi3_run: %s returned status %d\n", #call, (int)s_);   \
            return 1;                                                               \
        }                                                                           \
    } while (0)

#define LOAD(type, var, name)                                                       \
    type *var = (type *)symbol(lib, name);                                          \
    if (!var) {                                                                     \
        fprintf(stderr, "fmi3_run: %s is not exported by %s\n", name, argv[1]);     \
        return 1;                                                                   \
    }

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr,
                "usage: fmi3_run LIBRARY TOKEN RESOURCE_PATH STEPS H OUTPUT_VR [VR=VALUE ...]\n");
        return 2;
    }
    Library lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "fmi3_run: cannot load %s\n", argv[1]);
        return 1;
    }
    const char *token = argv[2];
    const char *resources = strcmp(argv[3], "-") == 0 ? NULL : argv[3];
    long steps = strtol(argv[4], NULL, 10);
    double h = strtod(argv[5], NULL);
    fmi3ValueReference output = (fmi3ValueReference)strtoul(argv[6], NULL, 10);

    LOAD(fmi3GetVersionTYPE, get_version, "fmi3GetVersion");
    LOAD(fmi3InstantiateCoSimulationTYPE, instantiate, "fmi3InstantiateCoSimulation");
    LOAD(fmi3EnterInitializationModeTYPE, enter_init, "fmi3EnterInitializationMode");
    LOAD(fmi3ExitInitializationModeTYPE, exit_init, "fmi3ExitInitializationMode");
    LOAD(fmi3SetFloat64TYPE, set_float64, "fmi3SetFloat64");
    LOAD(fmi3GetFloat64TYPE, get_float64, "fmi3GetFloat64");
    LOAD(fmi3DoStepTYPE, do_step, "fmi3DoStep");
    LOAD(fmi3TerminateTYPE, terminate, "fmi3Terminate");
    LOAD(fmi3FreeInstanceTYPE, free_instance, "fmi3FreeInstance");

    if (strncmp(get_version(), "3.", 2) != 0) {
        fprintf(stderr, "fmi3_run: version %s\n", get_version());
        return 1;
    }
    fmi3Instance c = instantiate("fmi3_run", token, resources, fmi3False, fmi3True, fmi3False,
                                 fmi3False, NULL, 0, NULL, logger, NULL);
    if (!c) {
        fprintf(stderr, "fmi3_run: fmi3InstantiateCoSimulation returned NULL\n");
        return 1;
    }
    CHECK(enter_init(c, fmi3False, 0.0, 0.0, fmi3True, (double)steps * h));
    for (int i = 7; i < argc; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq) {
            fprintf(stderr, "fmi3_run: %s is not VR=VALUE\n", argv[i]);
            return 2;
        }
        fmi3ValueReference vr = (fmi3ValueReference)strtoul(argv[i], NULL, 10);
        fmi3Float64 value = strtod(eq + 1, NULL);
        CHECK(set_float64(c, &vr, 1, &value, 1));
    }
    CHECK(exit_init(c));
    for (long k = 0; k < steps; k++) {
        double t = (double)k * h;
        fmi3Boolean event = fmi3True, terminate_now = fmi3True, early = fmi3True;
        fmi3Float64 last = -1.0;
        CHECK(do_step(c, t, h, fmi3True, &event, &terminate_now, &early, &last));
        if (event || terminate_now || early || last != t + h) {
            fprintf(stderr,
                    "fmi3_run: fmi3DoStep at %.17g: eventHandlingNeeded %d, terminateSimulation "
                    "%d, earlyReturn %d, lastSuccessfulTime %.17g (expected %.17g)\n",
                    t, (int)event, (int)terminate_now, (int)early, last, t + h);
            return 1;
        }
        fmi3Float64 value;
        CHECK(get_float64(c, &output, 1, &value, 1));
        uint64_t bits;
        memcpy(&bits, &value, sizeof bits);
        printf("%ld %016llx %.17g\n", k + 1, (unsigned long long)bits, value);
    }
    CHECK(terminate(c));
    free_instance(c);
    close_library(lib);
    return 0;
}
