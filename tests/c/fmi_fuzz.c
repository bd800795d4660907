/* fmi_fuzz.c: FMI 2.0 call-sequence fuzzer for BreathingTorso.
 *
 * Loads the FMU's shared library with dlopen and, in one process, runs many random
 * sequences of calls to the 34 common and co-simulation functions with random arguments:
 * NULL pointers, counts that do not match the arrays' NULL-ness, unknown and out-of-range
 * value references, NaN / infinite / huge values, bad strings (NULL, empty, not UTF-8),
 * out-of-range enumerations, calls in the wrong state (doStep before initialization, get
 * after terminate, setup after initialization), FMU states freed twice, used after free,
 * taken from another instance or made up, serialization into short or NULL buffers and
 * deserialization of truncated, corrupted and random bytes. The seeded generator (splitmix64)
 * makes every run reproducible.
 *
 * Every return must be a proper fmi2Status (OK, Warning, Discard, Error or Fatal: never
 * Pending, nothing else), every call with a NULL instance must return fmi2Error, every
 * log message must have a valid status and a non-NULL category and message, and the process
 * must not crash. Run it under AddressSanitizer (the harness built with -fsanitize=address:
 * ASan replaces malloc/free for the whole process, so invalid frees and double frees in the
 * library are caught too) and/or valgrind memcheck (which sees every access of the
 * uninstrumented Rust library as well).
 *
 * Only undefined behaviour that the standard leaves to the master is avoided: calls on an
 * instance after fmi2FreeInstance, and arrays shorter than the count passed with them.
 *
 * Usage: fmi_fuzz LIBRARY GUID SEED SEQUENCES CALLS_PER_SEQUENCE
 * Exit status 0 when every check held; prints a summary line "fuzz: ... calls ... ok".
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* FMI 2.0 types (fmi2TypesPlatform.h, fmi2FunctionTypes.h), "default" platform. */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
} fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

/* The functions, looked up by name. */
static const char *(*GetTypesPlatform)(void);
static const char *(*GetVersion)(void);
static fmi2Status (*SetDebugLogging)(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
static fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String,
                                    const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
static void (*FreeInstance)(fmi2Component);
static fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                                     fmi2Real);
static fmi2Status (*EnterInitializationMode)(fmi2Component);
static fmi2Status (*ExitInitializationMode)(fmi2Component);
static fmi2Status (*Terminate)(fmi2Component);
static fmi2Status (*Reset)(fmi2Component);
static fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
static fmi2Status (*GetInteger)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Integer[]);
static fmi2Status (*GetBoolean)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Boolean[]);
static fmi2Status (*GetString)(fmi2Component, const fmi2ValueReference[], size_t, fmi2String[]);
static fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
static fmi2Status (*SetInteger)(fmi2Component, const fmi2ValueReference[], size_t,
                                const fmi2Integer[]);
static fmi2Status (*SetBoolean)(fmi2Component, const fmi2ValueReference[], size_t,
                                const fmi2Boolean[]);
static fmi2Status (*SetString)(fmi2Component, const fmi2ValueReference[], size_t,
                               const fmi2String[]);
static fmi2Status (*GetFMUstate)(fmi2Component, fmi2FMUstate *);
static fmi2Status (*SetFMUstate)(fmi2Component, fmi2FMUstate);
static fmi2Status (*FreeFMUstate)(fmi2Component, fmi2FMUstate *);
static fmi2Status (*SerializedFMUstateSize)(fmi2Component, fmi2FMUstate, size_t *);
static fmi2Status (*SerializeFMUstate)(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
static fmi2Status (*DeSerializeFMUstate)(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate *);
static fmi2Status (*GetDirectionalDerivative)(fmi2Component, const fmi2ValueReference[], size_t,
                                              const fmi2ValueReference[], size_t, const fmi2Real[],
                                              fmi2Real[]);
static fmi2Status (*SetRealInputDerivatives)(fmi2Component, const fmi2ValueReference[], size_t,
                                             const fmi2Integer[], const fmi2Real[]);
static fmi2Status (*GetRealOutputDerivatives)(fmi2Component, const fmi2ValueReference[], size_t,
                                              const fmi2Integer[], fmi2Real[]);
static fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
static fmi2Status (*CancelStep)(fmi2Component);
static fmi2Status (*GetStatus)(fmi2Component, const fmi2StatusKind, fmi2Status *);
static fmi2Status (*GetRealStatus)(fmi2Component, const fmi2StatusKind, fmi2Real *);
static fmi2Status (*GetIntegerStatus)(fmi2Component, const fmi2StatusKind, fmi2Integer *);
static fmi2Status (*GetBooleanStatus)(fmi2Component, const fmi2StatusKind, fmi2Boolean *);
static fmi2Status (*GetStringStatus)(fmi2Component, const fmi2StatusKind, fmi2String *);

static void *library;

static void *symbol(const char *name) {
    void *p = dlsym(library, name);
    if (!p) {
        fprintf(stderr, "FAIL: %s is not exported (%s)\n", name, dlerror());
        exit(3);
    }
    return p;
}

#define LOAD(name) *(void **)(&name) = symbol("fmi2" #name)

static void load_all(void) {
    LOAD(GetTypesPlatform);
    LOAD(GetVersion);
    LOAD(SetDebugLogging);
    LOAD(Instantiate);
    LOAD(FreeInstance);
    LOAD(SetupExperiment);
    LOAD(EnterInitializationMode);
    LOAD(ExitInitializationMode);
    LOAD(Terminate);
    LOAD(Reset);
    LOAD(GetReal);
    LOAD(GetInteger);
    LOAD(GetBoolean);
    LOAD(GetString);
    LOAD(SetReal);
    LOAD(SetInteger);
    LOAD(SetBoolean);
    LOAD(SetString);
    LOAD(GetFMUstate);
    LOAD(SetFMUstate);
    LOAD(FreeFMUstate);
    LOAD(SerializedFMUstateSize);
    LOAD(SerializeFMUstate);
    LOAD(DeSerializeFMUstate);
    LOAD(GetDirectionalDerivative);
    LOAD(SetRealInputDerivatives);
    LOAD(GetRealOutputDerivatives);
    LOAD(DoStep);
    LOAD(CancelStep);
    LOAD(GetStatus);
    LOAD(GetRealStatus);
    LOAD(GetIntegerStatus);
    LOAD(GetBooleanStatus);
    LOAD(GetStringStatus);
}

/* ------------------------------------------------------------------------------------------ */
/* Seeded generator (splitmix64). */

static uint64_t rng_state;

static uint64_t next_u64(void) {
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static unsigned below(unsigned n) { return n ? (unsigned)(next_u64() % n) : 0; }
static double uniform(void) { return (double)(next_u64() >> 11) / 9007199254740992.0; }
static int chance(double p) { return uniform() < p; }

/* ------------------------------------------------------------------------------------------ */
/* Checks and counters. */

static unsigned long calls, by_status[6], log_messages, log_discards;
static const char *current = "";

static void fail(const char *what) {
    fprintf(stderr, "FAIL after %lu calls, in %s: %s\n", calls, current, what);
    exit(2);
}

static fmi2Status check(fmi2Status s) {
    calls++;
    if ((int)s < (int)fmi2OK || (int)s > (int)fmi2Fatal) {
        char m[64];
        snprintf(m, sizeof m, "improper status %d", (int)s);
        fail(m);
    }
    by_status[s]++;
    return s;
}

/* A call with a NULL instance must be refused with fmi2Error. */
static void check_null_instance(fmi2Status s) {
    if (check(s) != fmi2Error) fail("a NULL instance was not refused with fmi2Error");
}

static int verbose;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    log_messages++;
    if ((int)status < (int)fmi2OK || (int)status > (int)fmi2Fatal) fail("log status improper");
    if (!category || !message) fail("log category or message is NULL");
    char text[2048];
    va_list ap;
    va_start(ap, message);
    vsnprintf(text, sizeof text, message, ap);
    va_end(ap);
    if (status == fmi2Discard) {
        log_discards++;
        if (strlen(text) == 0) fail("a discard without an explanation");
    }
    if (verbose) fprintf(stderr, "  log [%s] %s: %s\n", category, name ? name : "(null)", text);
}

/* ------------------------------------------------------------------------------------------ */
/* Random arguments. */

#define MAX_INSTANCES 3
#define MAX_STATES 6
#define MAX_N 12

static const char *guid;
static fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};

typedef struct {
    fmi2Component c;
    double time; /* the master's idea of the instance's time */
    fmi2FMUstate states[MAX_STATES];
    fmi2FMUstate freed[MAX_STATES]; /* pointers freed already: a second free must be refused */
} Slot;

static Slot slots[MAX_INSTANCES];

/* Value references of the model's variables, and some that are not. */
static fmi2ValueReference random_vr(void) {
    switch (below(10)) {
    case 0: return below(9);               /* inputs */
    case 1: return 100 + below(33);        /* real parameters */
    case 2: return 200 + below(6);         /* integer parameters */
    case 3: return 300;                    /* string parameter */
    case 4: return 1000 + below(11);       /* outputs */
    case 5: return 2000 + below(768);      /* marker coordinates (180 outputs, then unknown) */
    case 6: return 3000 + below(3);        /* solver counters */
    case 7: return (fmi2ValueReference)next_u64();
    case 8: return UINT_MAX - below(3);
    default: return below(4000);
    }
}

static double random_real(void) {
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, -1e300, 1e308,
                                     DBL_MAX, -DBL_MAX, DBL_MIN, 2.0, 60.0, 1.75, 75.0, 1e-6};
    switch (below(6)) {
    case 0: return special[below(sizeof special / sizeof *special)];
    case 1: return NAN;
    case 2: return chance(0.5) ? INFINITY : -INFINITY;
    case 3: return (uniform() - 0.5) * 1e6;
    default: return uniform() * 2.0 - 0.5; /* near the ranges of activations and gains */
    }
}

static int random_int(void) {
    static const int special[] = {0, 1, 2, -1, 3, 16, 17, INT_MAX, INT_MIN, 10, 6};
    return chance(0.7) ? special[below(sizeof special / sizeof *special)] : (int)next_u64();
}

static char invalid_utf8[] = {(char)0xff, (char)0xfe, 'a', (char)0xc0, 0};
static char long_string[600];

static fmi2String random_string(void) {
    static const char *pool[] = {"", "x", "/nonexistent/recording.csv", "/etc/hostname", "/",
                                 "file:///tmp", "logEvents", "logCalls", "logStatusDiscard",
                                 "%s%s%s%n", "data/recordings/demo_quiet.csv"};
    switch (below(8)) {
    case 0: return NULL;
    case 1: return invalid_utf8;
    case 2: return long_string;
    default: return pool[below(sizeof pool / sizeof *pool)];
    }
}

/* A count and whether the arrays are NULL (a NULL array with a non-zero count is a
 * contract violation the FMU must refuse; a NULL array with zero count is allowed). */
static size_t random_count(void) { return chance(0.15) ? 0 : 1 + below(MAX_N); }

static Slot *random_slot(void) { return &slots[below(MAX_INSTANCES)]; }

/* The component of a slot, or NULL now and then (a slot may hold NULL itself). */
static fmi2Component component(Slot *s) { return chance(0.04) ? NULL : s->c; }

static fmi2FMUstate bogus_state(void) {
    static int local;
    switch (below(3)) {
    case 0: return (fmi2FMUstate)(uintptr_t)0x1234;
    case 1: return (fmi2FMUstate)&local;
    default: return (fmi2FMUstate)(uintptr_t)(next_u64() & ~(uint64_t)7);
    }
}

/* A state pointer: one of this slot's, one of another slot's, a freed one, made up, or NULL. */
static fmi2FMUstate random_state(Slot *s) {
    switch (below(6)) {
    case 0: case 1: case 2: return s->states[below(MAX_STATES)];
    case 3: return random_slot()->states[below(MAX_STATES)];
    case 4: return s->freed[below(MAX_STATES)];
    default: return chance(0.5) ? NULL : bogus_state();
    }
}

static void forget_state(fmi2FMUstate p) {
    /* a state freed by its instance: keep it as a dangling pointer for double-free tests */
    for (int i = 0; i < MAX_INSTANCES; i++)
        for (int k = 0; k < MAX_STATES; k++)
            if (slots[i].states[k] == p) {
                slots[i].states[k] = NULL;
                slots[i].freed[below(MAX_STATES)] = p;
            }
}

static void forget_instance(Slot *s) {
    /* the FMU frees an instance's states with it: they are dangling now, and another
     * instance must refuse them (only the address is compared, never dereferenced) */
    for (int k = 0; k < MAX_STATES; k++) {
        if (s->states[k]) s->freed[k] = s->states[k];
        s->states[k] = NULL;
    }
    s->c = NULL;
    s->time = 0.0;
}

/* ------------------------------------------------------------------------------------------ */
/* The calls. */

static void call_instantiate(Slot *s) {
    current = "fmi2Instantiate";
    if (s->c) {
        current = "fmi2FreeInstance";
        FreeInstance(s->c);
        calls++;
        forget_instance(s);
        current = "fmi2Instantiate";
    }
    fmi2String name = chance(0.9) ? "fuzz" : random_string();
    fmi2Type type = chance(0.9) ? fmi2CoSimulation : (fmi2Type)random_int();
    fmi2String g = chance(0.9) ? guid : random_string();
    fmi2String location = chance(0.5) ? NULL : chance(0.5) ? "file:///tmp/" : random_string();
    const fmi2CallbackFunctions *cb = chance(0.95) ? &callbacks : NULL;
    s->c = Instantiate(name, type, g, location, cb, random_int(), chance(0.3));
    calls++;
    s->time = 0.0;
    /* a name that is not UTF-8 is refused like an empty one */
    int valid = name && name[0] && name != invalid_utf8 && type == fmi2CoSimulation &&
                g == guid && cb;
    if (valid && !s->c) fail("a valid instantiation returned NULL");
    if (!valid && s->c && (type != fmi2CoSimulation || g != guid || !cb))
        fail("an invalid instantiation returned an instance");
}

/* Brings an instance to a cheap, steppable configuration now and then: level of detail 0. */
static void call_setup(Slot *s) {
    fmi2Component c = component(s);
    current = "fmi2SetInteger(level of detail)";
    fmi2ValueReference lod = 202; /* scene.level_of_detail */
    fmi2Integer zero = 0;
    fmi2Status st = check(SetInteger(c, &lod, 1, &zero));
    if (!c && st != fmi2Error) fail("NULL instance");
    current = "fmi2SetupExperiment";
    double start = chance(0.8) ? 0.0 : random_real();
    st = check(SetupExperiment(c, chance(0.5), random_real(), start, chance(0.3), random_real()));
    if (st == fmi2OK) s->time = start;
    current = "fmi2EnterInitializationMode";
    check(EnterInitializationMode(c));
    current = "fmi2ExitInitializationMode";
    check(ExitInitializationMode(c));
}

static void call_get_set(Slot *s) {
    fmi2Component c = component(s);
    fmi2ValueReference vr[MAX_N];
    size_t n = random_count();
    for (size_t i = 0; i < MAX_N; i++) vr[i] = random_vr();
    const fmi2ValueReference *vrp = chance(0.07) ? NULL : vr;
    fmi2Real r[MAX_N];
    fmi2Integer k[MAX_N];
    fmi2Boolean b[MAX_N];
    fmi2String str[MAX_N];
    for (size_t i = 0; i < MAX_N; i++) {
        r[i] = random_real();
        k[i] = random_int();
        b[i] = random_int();
        str[i] = random_string();
    }
    int null_values = chance(0.07);
    fmi2Status st = fmi2OK;
    switch (below(8)) {
    case 0:
        current = "fmi2GetReal";
        st = GetReal(c, vrp, n, null_values ? NULL : r);
        break;
    case 1:
        current = "fmi2GetInteger";
        st = GetInteger(c, vrp, n, null_values ? NULL : k);
        break;
    case 2:
        current = "fmi2GetBoolean";
        st = GetBoolean(c, vrp, n, null_values ? NULL : b);
        break;
    case 3:
        current = "fmi2GetString";
        st = GetString(c, vrp, n, null_values ? NULL : str);
        if (st == fmi2OK && !null_values) {
            for (size_t i = 0; i < n; i++) {
                if (!str[i]) fail("fmi2GetString returned OK with a NULL string");
                (void)strlen(str[i]); /* must be a readable NUL-terminated string */
            }
        }
        break;
    case 4:
        current = "fmi2SetReal";
        st = SetReal(c, vrp, n, null_values ? NULL : r);
        break;
    case 5:
        current = "fmi2SetInteger";
        st = SetInteger(c, vrp, n, null_values ? NULL : k);
        break;
    case 6:
        current = "fmi2SetBoolean";
        st = SetBoolean(c, vrp, n, null_values ? NULL : b);
        break;
    default:
        current = "fmi2SetString";
        st = SetString(c, vrp, n, null_values ? NULL : str);
        break;
    }
    if (c == NULL) check_null_instance(st);
    else if (check(st) == fmi2OK && n > 0 && (vrp == NULL || null_values))
        fail("a NULL array with a non-zero count was accepted");
}

static void call_do_step(Slot *s) {
    fmi2Component c = component(s);
    current = "fmi2DoStep";
    static const double steps[] = {1e-5, 1e-4, 1e-3, 1.0 / 56.0, 0.02, 0.1};
    /* improper step sizes: refused at once (a huge proper one would only take long) */
    static const double improper[] = {0.0, -0.0, -1.0, -1e-300, 1e-300, -DBL_MAX};
    double h = chance(0.85) ? steps[below(sizeof steps / sizeof *steps)]
               : chance(0.5) ? improper[below(sizeof improper / sizeof *improper)]
               : chance(0.5) ? NAN : (chance(0.5) ? INFINITY : -INFINITY);
    double t = chance(0.85) ? s->time : random_real();
    fmi2Status st = DoStep(c, t, h, random_int());
    if (!c) {
        check_null_instance(st);
        return;
    }
    check(st);
    if (st == fmi2OK) s->time = t + h;
    if (st == fmi2Discard) {
        fmi2Real last = NAN;
        current = "fmi2GetRealStatus";
        if (check(GetRealStatus(c, fmi2LastSuccessfulTime, &last)) == fmi2OK) s->time = last;
    }
}

static void call_status(Slot *s) {
    fmi2Component c = component(s);
    fmi2StatusKind kind = (fmi2StatusKind)(chance(0.8) ? (int)below(4) : random_int());
    int null_value = chance(0.1);
    fmi2Status value_s;
    fmi2Real value_r;
    fmi2Integer value_i;
    fmi2Boolean value_b;
    fmi2String value_str;
    fmi2Status st;
    switch (below(5)) {
    case 0:
        current = "fmi2GetStatus";
        st = GetStatus(c, kind, null_value ? NULL : &value_s);
        if (st == fmi2OK && !null_value && ((int)value_s < 0 || (int)value_s > 4))
            fail("fmi2GetStatus gave an improper status value");
        break;
    case 1:
        current = "fmi2GetRealStatus";
        st = GetRealStatus(c, kind, null_value ? NULL : &value_r);
        break;
    case 2:
        current = "fmi2GetIntegerStatus";
        st = GetIntegerStatus(c, kind, null_value ? NULL : &value_i);
        break;
    case 3:
        current = "fmi2GetBooleanStatus";
        st = GetBooleanStatus(c, kind, null_value ? NULL : &value_b);
        break;
    default:
        current = "fmi2GetStringStatus";
        st = GetStringStatus(c, kind, null_value ? NULL : &value_str);
        break;
    }
    if (!c) check_null_instance(st);
    else if (check(st) == fmi2OK && null_value) fail("a NULL value pointer was accepted");
}

static void call_fmu_state(Slot *s) {
    fmi2Component c = component(s);
    fmi2Status st;
    switch (below(6)) {
    case 0: { /* get, into a fresh slot or over an existing state */
        current = "fmi2GetFMUstate";
        int k = below(MAX_STATES);
        fmi2FMUstate *slot = chance(0.05) ? NULL : &s->states[k];
        fmi2FMUstate before = slot ? *slot : NULL;
        if (slot && chance(0.1)) *slot = bogus_state(); /* neither NULL nor ours: refused */
        fmi2FMUstate attempted = slot ? *slot : NULL;
        st = GetFMUstate(c, slot);
        if (!c) check_null_instance(st);
        else check(st);
        if (slot && *slot == attempted && attempted != before) *slot = before;
        break;
    }
    case 1:
        current = "fmi2SetFMUstate";
        st = SetFMUstate(c, random_state(s));
        if (!c) check_null_instance(st);
        else if (check(st) == fmi2OK) {
            fmi2Real t = NAN;
            if (GetRealStatus(c, fmi2LastSuccessfulTime, &t) == fmi2OK) s->time = t;
            calls++;
        }
        break;
    case 2: { /* free: own states, another's, freed ones (double free), made up, NULL */
        current = "fmi2FreeFMUstate";
        fmi2FMUstate p = random_state(s);
        fmi2FMUstate copy = p;
        st = FreeFMUstate(c, chance(0.05) ? NULL : &copy);
        if (!c) {
            check_null_instance(st);
            break;
        }
        if (check(st) == fmi2OK && p) {
            if (copy != NULL) fail("fmi2FreeFMUstate did not set the pointer to NULL");
            forget_state(p);
        }
        break;
    }
    case 3: {
        current = "fmi2SerializedFMUstateSize";
        size_t size = 0;
        st = SerializedFMUstateSize(c, random_state(s), chance(0.1) ? NULL : &size);
        if (!c) check_null_instance(st);
        else check(st);
        break;
    }
    default: { /* serialize (short, NULL or big enough buffer), mutate, deserialize */
        current = "fmi2SerializeFMUstate";
        fmi2FMUstate p = random_state(s);
        size_t size = 0;
        if (c && SerializedFMUstateSize(c, p, &size) != fmi2OK) size = 64 + below(64);
        calls++;
        size_t cap = chance(0.2) ? size / 2 : size;
        fmi2Byte *buf = malloc(cap ? cap : 1);
        if (!buf) fail("out of memory");
        st = SerializeFMUstate(c, p, chance(0.05) ? NULL : buf, cap);
        if (!c) check_null_instance(st);
        else if (check(st) != fmi2OK) {
            for (size_t i = 0; i < cap; i++) buf[i] = (fmi2Byte)next_u64();
        }
        size_t len = cap;
        switch (below(5)) {
        case 0: len = cap ? below((unsigned)cap) : 0; break; /* truncated */
        case 1: if (cap) buf[below((unsigned)cap)] ^= (fmi2Byte)(1u << below(8)); break;
        case 2: if (cap > 30) memset(buf + 12, 0xff, 8); break; /* huge length field */
        default: break;
        }
        current = "fmi2DeSerializeFMUstate";
        int k = below(MAX_STATES);
        fmi2FMUstate *slot = chance(0.05) ? NULL : &s->states[k];
        st = DeSerializeFMUstate(c, chance(0.05) ? NULL : buf, len, slot);
        if (!c) check_null_instance(st);
        else check(st);
        free(buf);
        break;
    }
    }
}

static void call_misc(Slot *s) {
    fmi2Component c = component(s);
    fmi2Status st;
    fmi2ValueReference vr[MAX_N];
    fmi2Real r[MAX_N];
    fmi2Integer order[MAX_N];
    for (size_t i = 0; i < MAX_N; i++) {
        vr[i] = random_vr();
        r[i] = random_real();
        order[i] = random_int();
    }
    size_t n = random_count();
    switch (below(9)) {
    case 0: {
        current = "fmi2SetDebugLogging";
        fmi2String cats[MAX_N];
        for (size_t i = 0; i < MAX_N; i++) cats[i] = random_string();
        st = SetDebugLogging(c, random_int(), n, chance(0.1) ? NULL : cats);
        break;
    }
    case 1: current = "fmi2Terminate"; st = Terminate(c); break;
    case 2:
        current = "fmi2Reset";
        st = Reset(c);
        if (st == fmi2OK) s->time = 0.0;
        break;
    case 3: current = "fmi2CancelStep"; st = CancelStep(c); break;
    case 4:
        current = "fmi2GetDirectionalDerivative";
        st = GetDirectionalDerivative(c, vr, n, vr, n, r, r);
        break;
    case 5:
        current = "fmi2SetRealInputDerivatives";
        st = SetRealInputDerivatives(c, vr, n, order, r);
        break;
    case 6:
        current = "fmi2GetRealOutputDerivatives";
        st = GetRealOutputDerivatives(c, vr, n, order, r);
        break;
    case 7:
        current = "fmi2SetupExperiment";
        st = SetupExperiment(c, random_int(), random_real(), random_real(), random_int(),
                             random_real());
        break;
    default:
        current = "fmi2EnterInitializationMode/fmi2ExitInitializationMode";
        st = chance(0.5) ? EnterInitializationMode(c) : ExitInitializationMode(c);
        break;
    }
    if (!c) check_null_instance(st);
    else check(st);
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: %s LIBRARY GUID SEED SEQUENCES CALLS_PER_SEQUENCE\n", argv[0]);
        return 64;
    }
    verbose = getenv("FMI_FUZZ_VERBOSE") != NULL;
    library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "FAIL: dlopen %s: %s\n", argv[1], dlerror());
        return 3;
    }
    load_all();
    guid = argv[2];
    unsigned long seed = strtoul(argv[3], NULL, 10);
    long sequences = strtol(argv[4], NULL, 10);
    long per_sequence = strtol(argv[5], NULL, 10);
    memset(long_string, 'a', sizeof long_string - 1);
    if (strcmp(GetVersion(), "2.0") != 0) fail("fmi2GetVersion is not 2.0");
    if (strcmp(GetTypesPlatform(), "default") != 0) fail("fmi2GetTypesPlatform is not default");

    for (long q = 0; q < sequences; q++) {
        rng_state = seed * 1000003ull + (uint64_t)q;
        /* every sequence starts with fresh instances */
        for (int i = 0; i < MAX_INSTANCES; i++) call_instantiate(&slots[i]);
        for (long k = 0; k < per_sequence; k++) {
            Slot *s = random_slot();
            if (!s->c && chance(0.5)) {
                call_instantiate(s);
                continue;
            }
            switch (below(20)) {
            case 0: call_instantiate(s); break;
            case 1: case 2: call_setup(s); break;
            case 3: case 4: case 5: case 6: case 7: call_get_set(s); break;
            case 8: case 9: case 10: call_do_step(s); break;
            case 11: case 12: call_status(s); break;
            case 13: case 14: case 15: case 16: call_fmu_state(s); break;
            default: call_misc(s); break;
            }
        }
        current = "fmi2FreeInstance";
        for (int i = 0; i < MAX_INSTANCES; i++) {
            FreeInstance(slots[i].c);
            calls++;
            forget_instance(&slots[i]);
            memset(slots[i].freed, 0, sizeof slots[i].freed);
        }
        FreeInstance(NULL);
        calls++;
    }
    printf("fuzz: seed %lu, %ld sequences x %ld calls: %lu calls (OK %lu, Warning %lu, Discard %lu, "
           "Error %lu, Fatal %lu), %lu log messages (%lu discards explained): ok\n",
           seed, sequences, per_sequence, calls, by_status[0], by_status[1], by_status[2],
           by_status[3], by_status[4], log_messages, log_discards);
    /* the library stays loaded: its process-wide tables (the variable table) live until
     * exit, and leak checkers then see them as reachable */
    return 0;
}
