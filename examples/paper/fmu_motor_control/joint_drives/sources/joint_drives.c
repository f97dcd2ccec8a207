/* FMI 2.0 glue of the joint drives (drives.h): one FMU for model exchange and
 * co-simulation. Built from this source by `ejsgen build` (FMPy's build helper and the
 * system's C compiler); no binary is stored in the repository.
 *
 * A failing call logs why through the environment's logger and returns fmi2Error:
 * an armature current above i_max (the amplifier's current limit), or setting a fixed
 * parameter after initialization.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "drives.h"

#define GUID "{6d1f3a52-4c1e-4f0b-9a57-3e5d2c0b7a12}"

typedef enum { MODE_INSTANTIATED, MODE_INIT, MODE_EVENT, MODE_CONTINUOUS, MODE_STEP, MODE_TERMINATED, MODE_ERROR } Mode;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    fmi2Type kind;
    fmi2Boolean logging;
    Mode mode;
    double time;
    double r[N_VARS];
} Drives;

static void say(Drives *c, fmi2Status status, const char *category, const char *fmt, ...) {
    char text[512];
    va_list args;
    if (c == NULL || c->cb.logger == NULL) return;
    if (status == fmi2OK && !c->logging) return;
    va_start(args, fmt);
    vsnprintf(text, sizeof text, fmt, args);
    va_end(args);
    c->cb.logger(c->cb.componentEnvironment, c->name, status, category, "%s", text);
}

static fmi2Status fail(Drives *c, const char *fmt, const char *what) {
    say(c, fmi2Error, "logStatusError", fmt, what);
    c->mode = MODE_ERROR;
    return fmi2Error;
}

static int is_fixed_parameter(fmi2ValueReference vr) {
    return vr == VR_R || vr == VR_LA || vr == VR_KT || vr == VR_KB || (vr >= VR_G && vr < VR_G + N_JOINTS);
}

static int is_settable(fmi2ValueReference vr) {
    return vr < VR_TAU || vr >= VR_KP || (vr >= VR_I && vr < VR_DER_I);
}

static fmi2Status check_current(Drives *c) {
    int j = drives_overcurrent(c->r);
    if (j < 0) return fmi2OK;
    say(c, fmi2Error, "logStatusError",
        "joint %d: armature current %.3g A exceeds the amplifier's limit i_max = %.3g A at t = %.4g s",
        j + 1, c->r[VR_I + j], c->r[VR_IMAX], c->time);
    c->mode = MODE_ERROR;
    return fmi2Error;
}

/* -- common functions ------------------------------------------------------------------ */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    (void)n; (void)categories;
    ((Drives *)c)->logging = on;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type kind, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible, fmi2Boolean logging) {
    Drives *c;
    (void)resources; (void)visible;
    if (functions == NULL || guid == NULL || strcmp(guid, GUID) != 0) {
        if (functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "wrong GUID %s (expected %s)", guid ? guid : "(null)", GUID);
        return NULL;
    }
    c = (Drives *)calloc(1, sizeof(Drives));
    if (c == NULL) return NULL;
    c->cb = *functions;
    c->name = (char *)malloc(strlen(name ? name : "") + 1);
    strcpy(c->name, name ? name : "");
    c->kind = kind;
    c->logging = logging;
    c->mode = MODE_INSTANTIATED;
    drives_defaults(c->r);
    drives_compute(c->r);
    return c;
}

void fmi2FreeInstance(fmi2Component c) {
    Drives *d = (Drives *)c;
    if (d == NULL) return;
    free(d->name);
    free(d);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    ((Drives *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ((Drives *)c)->mode = MODE_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Drives *d = (Drives *)c;
    drives_compute(d->r);
    d->mode = d->kind == fmi2ModelExchange ? MODE_EVENT : MODE_STEP;
    return check_current(d);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ((Drives *)c)->mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Drives *d = (Drives *)c;
    drives_defaults(d->r);
    drives_compute(d->r);
    d->time = 0.0;
    d->mode = MODE_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Drives *d = (Drives *)c;
    size_t k;
    drives_compute(d->r);
    for (k = 0; k < nvr; k++) {
        if (vr[k] >= N_VARS) return fail(d, "%s", "fmi2GetReal: unknown value reference");
        value[k] = d->r[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Drives *d = (Drives *)c;
    size_t k;
    for (k = 0; k < nvr; k++) {
        if (vr[k] >= N_VARS || !is_settable(vr[k])) return fail(d, "%s", "fmi2SetReal: the variable cannot be set");
        if (is_fixed_parameter(vr[k]) && d->mode != MODE_INSTANTIATED && d->mode != MODE_INIT) {
            say(d, fmi2Error, "logStatusError", "fmi2SetReal: value reference %u is a fixed parameter: set it before initialization", (unsigned)vr[k]);
            return fmi2Error;
        }
        d->r[vr[k]] = value[k];
    }
    return fmi2OK;
}

#define NO_VARIABLES(fn, type)                                                                     \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, type value[]) {      \
        (void)vr; (void)value;                                                                     \
        if (nvr == 0) return fmi2OK;                                                               \
        return fail((Drives *)c, "%s: this FMU has only Real variables", #fn);                     \
    }
NO_VARIABLES(fmi2GetInteger, fmi2Integer)
NO_VARIABLES(fmi2GetBoolean, fmi2Boolean)
NO_VARIABLES(fmi2GetString, fmi2String)
NO_VARIABLES(fmi2SetInteger, const fmi2Integer)
NO_VARIABLES(fmi2SetBoolean, const fmi2Boolean)
NO_VARIABLES(fmi2SetString, const fmi2String)

/* optional capabilities this FMU does not have (canGetAndSetFMUstate="false", ...) */
#define UNSUPPORTED(name, ...)                                                                     \
    fmi2Status name(fmi2Component c, __VA_ARGS__) {                                                \
        say((Drives *)c, fmi2Error, "logStatusError", "%s is not supported", #name);               \
        return fmi2Error;                                                                          \
    }
UNSUPPORTED(fmi2GetFMUstate, fmi2FMUstate *s)
UNSUPPORTED(fmi2SetFMUstate, fmi2FMUstate s)
UNSUPPORTED(fmi2FreeFMUstate, fmi2FMUstate *s)
UNSUPPORTED(fmi2SerializedFMUstateSize, fmi2FMUstate s, size_t *n)
UNSUPPORTED(fmi2SerializeFMUstate, fmi2FMUstate s, fmi2Byte b[], size_t n)
UNSUPPORTED(fmi2DeSerializeFMUstate, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
UNSUPPORTED(fmi2GetDirectionalDerivative, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference k[], size_t nk, const fmi2Real dk[], fmi2Real du[])
UNSUPPORTED(fmi2SetRealInputDerivatives, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[], const fmi2Real value[])
UNSUPPORTED(fmi2GetRealOutputDerivatives, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[], fmi2Real value[])
UNSUPPORTED(fmi2GetStatus, const fmi2StatusKind s, fmi2Status *value)
UNSUPPORTED(fmi2GetIntegerStatus, const fmi2StatusKind s, fmi2Integer *value)
UNSUPPORTED(fmi2GetBooleanStatus, const fmi2StatusKind s, fmi2Boolean *value)
UNSUPPORTED(fmi2GetStringStatus, const fmi2StatusKind s, fmi2String *value)

fmi2Status fmi2CancelStep(fmi2Component c) {
    say((Drives *)c, fmi2Error, "logStatusError", "%s is not supported", "fmi2CancelStep");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = ((Drives *)c)->time;
    return fmi2OK;
}

/* -- model exchange ---------------------------------------------------------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    ((Drives *)c)->mode = MODE_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)c;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    ((Drives *)c)->mode = MODE_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetPrior, fmi2Boolean *enterEventMode, fmi2Boolean *terminate) {
    (void)noSetPrior;
    *enterEventMode = fmi2False;
    *terminate = fmi2False;
    return check_current((Drives *)c);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    ((Drives *)c)->time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Drives *d = (Drives *)c;
    size_t k;
    if (nx != N_STATES) return fail(d, "%s", "fmi2SetContinuousStates: this FMU has 6 continuous states");
    for (k = 0; k < nx; k++) d->r[drives_state_vr[k]] = x[k];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    Drives *d = (Drives *)c;
    size_t k;
    if (nx != N_STATES) return fail(d, "%s", "fmi2GetDerivatives: this FMU has 6 continuous states");
    drives_compute(d->r);
    for (k = 0; k < nx; k++) dx[k] = d->r[drives_der_vr[k]];
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz) {
    (void)c; (void)z;
    return nz == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Drives *d = (Drives *)c;
    size_t k;
    if (nx != N_STATES) return fail(d, "%s", "fmi2GetContinuousStates: this FMU has 6 continuous states");
    for (k = 0; k < nx; k++) x[k] = d->r[drives_state_vr[k]];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    size_t k;
    (void)c;
    for (k = 0; k < nx; k++) x[k] = 1.0;
    return fmi2OK;
}

/* -- co-simulation ------------------------------------------------------------------------ */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Drives *d = (Drives *)c;
    (void)noSetPrior;
    if (h < 0.0) return fail(d, "%s", "fmi2DoStep: negative communication step");
    drives_advance(d->r, h);
    d->time = t + h;
    return check_current(d);
}
