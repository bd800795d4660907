/* fmu_overhead.c: what the FMI 2.0 layer adds to the model's own work, per communication step.
 *
 * The same shared object (an FMU's binaries/linux64/BreathingTorso.so) exports both the FMI
 * 2.0 functions and the C ABI (bt_*). The same scene is run both ways, FRAMES communication
 * steps of 1/RATE s, reading the four volumes and the 60 markers of the default grid at every
 * step:
 *   fmi:    fmi2DoStep, then one fmi2GetReal of the 4 + 180 value references;
 *   native: bt_advance_to, four bt_read and one bt_read_markers.
 * Runs alternate (fmi, native, fmi, ...) REPEATS times; the wall time of each run, of the
 * fmi2DoStep calls and of the fmi2GetReal calls are printed as medians, with the added time
 * per step. Exit status 1 when the last step's 184 values differ between the two ways
 * (the same model in the same library: they must be identical, bit for bit).
 *
 * Usage: fmu_overhead LIBRARY GUID [FRAMES [REPEATS [METHOD]]]
 *   METHOD: solver.method (0 Dormand-Prince, 4 quasi-static); default 0.
 * The drive is that of python/bench_fmu.py (ribs 0.2, diaphragm 0.25, phase 0.1).
 * Build: cc -O2 -I FMI2_HEADERS fmu_overhead.c -ldl  (scripts/bench-fmu-overhead.sh).
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2FunctionTypes.h"

#define RATE 56.0
#define VOLUMES 4
#define MARKER_VALUES 180
#define MAX_REPEATS 64

/* The C ABI's entry points used here (include/breathing_torso.h); the configuration is
 * treated as an opaque buffer filled by bt_config_default and changed through bt_config_set. */
typedef void *(*bt_create_t)(const void *config);
typedef void (*bt_destroy_t)(void *h);
typedef int (*bt_advance_to_t)(void *h, double t, void *stats);
typedef int (*bt_read_t)(void *h, uint32_t vr, double *value);
typedef int (*bt_read_markers_t)(void *h, double *xyz, size_t capacity, size_t *count);
typedef const char *(*bt_last_error_t)(void *h);
typedef int (*bt_config_default_t)(void *config);
typedef int (*bt_config_set_t)(void *config, const char *name, double value);

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n) {
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

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

#define SYM(type, var, name)                                                        \
    type var = (type)dlsym(lib, name);                                              \
    if (!var) {                                                                     \
        fprintf(stderr, "fmu_overhead: %s is not exported\n", name);                 \
        return 1;                                                                   \
    }

static void *lib;
static const char *guid;
static long frames;
static double method;
static double first_read;
/* the last step's values read each way: the FMU and the C ABI run the same model */
static double last_fmi[VOLUMES + MARKER_VALUES], last_native[VOLUMES + MARKER_VALUES];

/* One FMI run; step and read times accumulated separately. */
static int run_fmi(double *total, double *stepping, double *reading, double *again) {
    SYM(fmi2InstantiateTYPE *, instantiate, "fmi2Instantiate");
    SYM(fmi2SetupExperimentTYPE *, setup, "fmi2SetupExperiment");
    SYM(fmi2EnterInitializationModeTYPE *, enter, "fmi2EnterInitializationMode");
    SYM(fmi2ExitInitializationModeTYPE *, exit_init, "fmi2ExitInitializationMode");
    SYM(fmi2SetRealTYPE *, set_real, "fmi2SetReal");
    SYM(fmi2GetRealTYPE *, get_real, "fmi2GetReal");
    SYM(fmi2SetIntegerTYPE *, set_integer, "fmi2SetInteger");
    SYM(fmi2DoStepTYPE *, do_step, "fmi2DoStep");
    SYM(fmi2FreeInstanceTYPE *, free_instance, "fmi2FreeInstance");
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference vrs[VOLUMES + MARKER_VALUES];
    fmi2Real out[VOLUMES + MARKER_VALUES];
    for (int i = 0; i < VOLUMES; i++) vrs[i] = 1000 + (fmi2ValueReference)i;
    for (int i = 0; i < MARKER_VALUES; i++) vrs[VOLUMES + i] = 2000 + (fmi2ValueReference)i;
    const fmi2ValueReference pvr[] = {111, 113, 114}, mvr = 205;
    const fmi2Real pval[] = {0.2, 0.25, 0.1};
    const fmi2Integer mval = (fmi2Integer)method;
    double t0 = now();
    fmi2Component c = instantiate("overhead", fmi2CoSimulation, guid, NULL, &cb, fmi2False,
                                  fmi2False);
    if (!c) return 1;
    if (setup(c, fmi2False, 0.0, 0.0, fmi2True, (double)frames / RATE) != fmi2OK ||
        enter(c) != fmi2OK || set_real(c, pvr, 3, pval) != fmi2OK ||
        set_integer(c, &mvr, 1, &mval) != fmi2OK || exit_init(c) != fmi2OK)
        return 1;
    *stepping = *reading = *again = 0.0;
    for (long k = 0; k < frames; k++) {
        double a = now();
        if (do_step(c, (double)k / RATE, 1.0 / RATE, fmi2True) != fmi2OK) return 1;
        if (k == 0) a = now(); /* as in the native loop, the first step is left out */
        double b = now();
        if (get_real(c, vrs, VOLUMES + MARKER_VALUES, out) != fmi2OK) return 1;
        double e = now();
        /* the same values again: the layer alone, the model's observation already made */
        if (get_real(c, vrs, VOLUMES + MARKER_VALUES, out) != fmi2OK) return 1;
        *again += now() - e;
        *stepping += b - a;
        if (k == 0)
            first_read = e - b; /* builds the marker model (the skin) */
        else
            *reading += e - b;
    }
    memcpy(last_fmi, out, sizeof out);
    free_instance(c);
    *total = now() - t0;
    return 0;
}

static int run_native(double *total, double *looping, double *again) {
    SYM(bt_create_t, create, "bt_create");
    SYM(bt_destroy_t, destroy, "bt_destroy");
    SYM(bt_advance_to_t, advance, "bt_advance_to");
    SYM(bt_read_t, read, "bt_read");
    SYM(bt_read_markers_t, read_markers, "bt_read_markers");
    SYM(bt_last_error_t, last_error, "bt_last_error");
    /* bt_create(NULL) is refused; the default configuration with the drive set comes from
     * bt_config_default and bt_config_set (by variable name, as in the FMU). */
    SYM(bt_config_default_t, config_default, "bt_config_default");
    SYM(bt_config_set_t, config_set, "bt_config_set");
    static unsigned char config[1 << 16];
    memset(config, 0, sizeof config);
    config_default(config);
    if (config_set(config, "drive.ribs.amplitude", 0.2) ||
        config_set(config, "drive.diaphragm.amplitude", 0.25) ||
        config_set(config, "drive.diaphragm.phase", 0.1) ||
        config_set(config, "solver.method", method)) {
        fprintf(stderr, "fmu_overhead: bt_config_set failed\n");
        return 1;
    }
    double values[VOLUMES], xyz[MARKER_VALUES];
    *again = 0.0;
    double t0 = now();
    void *h = create(config);
    if (!h) return 1;
    /* the first step builds the model (bt_create only checks the configuration) and its
     * first read the marker model; the FMU builds both in fmi2Instantiate and its first
     * fmi2GetReal: both are left out of the loop times compared */
    if (advance(h, 1.0 / RATE, NULL) != 0 || read_markers(h, xyz, MARKER_VALUES, NULL) != 0)
        return 1;
    double l0 = now();
    for (long k = 2; k <= frames; k++) {
        /* the end time the FMU computes, currentCommunicationPoint + communicationStepSize */
        if (advance(h, (double)(k - 1) / RATE + 1.0 / RATE, NULL) != 0) {
            fprintf(stderr, "fmu_overhead: %s\n", last_error(h));
            return 1;
        }
        for (int i = 0; i < VOLUMES; i++) read(h, 1000 + (uint32_t)i, &values[i]);
        if (read_markers(h, xyz, MARKER_VALUES, NULL) != 0) return 1;
        double e = now();
        for (int i = 0; i < VOLUMES; i++) read(h, 1000 + (uint32_t)i, &values[i]);
        if (read_markers(h, xyz, MARKER_VALUES, NULL) != 0) return 1;
        *again += now() - e;
    }
    *looping = now() - l0;
    memcpy(last_native, values, sizeof values);
    memcpy(last_native + VOLUMES, xyz, sizeof xyz);
    destroy(h);
    *total = now() - t0;
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: fmu_overhead LIBRARY GUID [FRAMES [REPEATS [METHOD]]]\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "fmu_overhead: cannot load %s: %s\n", argv[1], dlerror());
        return 1;
    }
    guid = argv[2];
    frames = argc > 3 ? strtol(argv[3], NULL, 10) : 1000;
    int repeats = argc > 4 ? atoi(argv[4]) : 5;
    method = argc > 5 ? strtod(argv[5], NULL) : 0.0;
    if (repeats < 1 || repeats > MAX_REPEATS || frames < 1) return 2;
    double fmi[MAX_REPEATS], step[MAX_REPEATS], readt[MAX_REPEATS], native[MAX_REPEATS];
    double fmi_again[MAX_REPEATS], native_again[MAX_REPEATS], loop[MAX_REPEATS], fmi_loop[MAX_REPEATS];
    for (int r = 0; r < repeats; r++) {
        if (run_fmi(&fmi[r], &step[r], &readt[r], &fmi_again[r]) ||
            run_native(&native[r], &loop[r], &native_again[r])) {
            fprintf(stderr, "fmu_overhead: a run failed\n");
            return 1;
        }
    }
    for (int r = 0; r < repeats; r++) fmi_loop[r] = step[r] + readt[r] + fmi_again[r];
    double added = 1e6 * (median(fmi_loop, repeats) - median(loop, repeats)) / (double)(frames - 1);
    double f = median(fmi, repeats), n = median(native, repeats);
    printf("%ld frames at %g Hz, 4 volumes + 60 markers, solver.method %g, median of %d\n",
           frames, RATE, method, repeats);
    printf("  fmi run          : %.4f s (fmi2DoStep %.4f s, fmi2GetReal %.4f s)\n", f,
           median(step, repeats), median(readt, repeats));
    printf("  native run       : %.4f s (whole runs: creation and the model build too)\n", n);
    printf("  first fmi2GetReal: %.4f s (builds the marker model, last run)\n", first_read);
    printf("  fmi2GetReal/step : %.2f us (first read of a step: observation and markers)\n",
           1e6 * median(readt, repeats) / (double)(frames - 1));
    printf("  read again/step  : %.2f us fmi2GetReal, %.2f us bt_read + bt_read_markers\n",
           1e6 * median(fmi_again, repeats) / (double)frames,
           1e6 * median(native_again, repeats) / (double)frames);
    printf("  steps 2..%ld      : fmi %.4f s, native %.4f s (each step reads twice)\n", frames,
           median(fmi_loop, repeats), median(loop, repeats));
    printf("  added per step   : %.2f us\n", added);
    if (memcmp(last_fmi, last_native, sizeof last_fmi) != 0) {
        for (int i = 0; i < VOLUMES + MARKER_VALUES; i++)
            if (memcmp(&last_fmi[i], &last_native[i], sizeof(double)) != 0) {
                fprintf(stderr, "fmu_overhead: value %d differs at the last step: fmi %.17g, native %.17g\n",
                        i, last_fmi[i], last_native[i]);
                break;
            }
        return 1;
    }
    printf("  last step        : the 184 values identical, bit for bit, both ways\n");
    return 0;
}
