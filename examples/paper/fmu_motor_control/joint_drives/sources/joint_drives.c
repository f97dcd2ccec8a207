/* FMI 2.0 glue of the joint drives (drives.h): one FMU for model exchange and
 * co-simulation. Built from this source by `ejsgen build` (FMPy's build helper and the
 * system's C compiler); no binary is stored in the repository.
 *
 * A failing call logs why through the environment's logger and returns fmi2Error:
 * an armature current above i_max (the amplifier's current limit), or a call the FMI 2.0
 * state machine forbids in the FMU's current state, with the masks of the Modelica
 * Association's Reference FMUs (fmi2Functions.c): a tunable parameter is set only before
 * initialization, in initialization mode, in event mode (model exchange) or between steps
 * (co-simulation); a fixed parameter or a start value only before initialization ends;
 * setTime only in event or continuous-time mode, setContinuousStates and
 * completedIntegratorStep only in continuous-time mode, newDiscreteStates only in event
 * mode, doStep only between steps. So an importer calling in the wrong order is caught.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "drives.h"

#define GUID "{6d1f3a52-4c1e-4f0b-9a57-3e5d2c0b7a12}"

typedef enum { MODE_INSTANTIATED, MODE_INIT, MODE_EVENT, MODE_CONTINUOUS, MODE_STEP, MODE_TERMINATED, MODE_ERROR } Mode;
static const char *MODE_NAMES[] = {"the instantiated state", "initialization mode", "event mode", "continuous-time mode", "step mode", "the terminated state", "an error state"};

/* the states a call is allowed in (bits of Mode), as the Reference FMUs' MASK_fmi2... */
#define IN(m) (1 << (m))
#define MASK_GET (IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP) | IN(MODE_TERMINATED) | IN(MODE_ERROR))
#define MASK_SET_CONTINUOUS_INPUT (IN(MODE_INSTANTIATED) | IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP))
#define MASK_SET_TUNABLE (IN(MODE_INSTANTIATED) | IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_STEP))
#define MASK_SET_FIXED (IN(MODE_INSTANTIATED) | IN(MODE_INIT))
#define MASK_TERMINATE (IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP) | IN(MODE_ERROR))

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

/* a call the FMU's state forbids: logged, fmi2Error (the state is kept, as the Reference FMUs do) */
static int allowed(Drives *c, const char *fn, int mask) {
    if (c == NULL) return 0;
    if (mask & IN(c->mode)) return 1;
    say(c, fmi2Error, "logStatusError", "%s: Illegal call sequence (the FMU is in %s)", fn, MODE_NAMES[c->mode]);
    return 0;
}

static const char *role(fmi2ValueReference vr) {
    if (vr < VR_TAU) return "an input";
    if (vr >= VR_I && vr < VR_DER_I) return "a state (its start value)";
    if (vr == VR_KP || vr == VR_KI || vr == VR_KD || vr == VR_KA || vr == VR_VMAX || vr == VR_IMAX) return "a tunable parameter";
    return "a fixed parameter";
}

static int set_mask(fmi2ValueReference vr) {
    if (vr < VR_TAU) return MASK_SET_CONTINUOUS_INPUT;
    if (vr >= VR_I && vr < VR_DER_I) return MASK_SET_FIXED;
    if (vr == VR_KP || vr == VR_KI || vr == VR_KD || vr == VR_KA || vr == VR_VMAX || vr == VR_IMAX) return MASK_SET_TUNABLE;
    return MASK_SET_FIXED;
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
    if (!allowed((Drives *)c, "fmi2SetupExperiment", IN(MODE_INSTANTIATED))) return fmi2Error;
    ((Drives *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    if (!allowed((Drives *)c, "fmi2EnterInitializationMode", IN(MODE_INSTANTIATED))) return fmi2Error;
    ((Drives *)c)->mode = MODE_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Drives *d = (Drives *)c;
    if (!allowed(d, "fmi2ExitInitializationMode", IN(MODE_INIT))) return fmi2Error;
    drives_compute(d->r);
    d->mode = d->kind == fmi2ModelExchange ? MODE_EVENT : MODE_STEP;
    return check_current(d);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    if (!allowed((Drives *)c, "fmi2Terminate", MASK_TERMINATE)) return fmi2Error;
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
    if (!allowed(d, "fmi2GetReal", MASK_GET)) return fmi2Error;
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
        if (!(set_mask(vr[k]) & IN(d->mode))) {
            say(d, fmi2Error, "logStatusError", "fmi2SetReal: value reference %u is %s and cannot be set in %s", (unsigned)vr[k], role(vr[k]), MODE_NAMES[d->mode]);
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
    if (!allowed((Drives *)c, "fmi2EnterEventMode", IN(MODE_EVENT) | IN(MODE_CONTINUOUS))) return fmi2Error;
    ((Drives *)c)->mode = MODE_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    if (!allowed((Drives *)c, "fmi2NewDiscreteStates", IN(MODE_EVENT))) return fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    if (!allowed((Drives *)c, "fmi2EnterContinuousTimeMode", IN(MODE_EVENT))) return fmi2Error;
    ((Drives *)c)->mode = MODE_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetPrior, fmi2Boolean *enterEventMode, fmi2Boolean *terminate) {
    (void)noSetPrior;
    *enterEventMode = fmi2False;
    *terminate = fmi2False;
    if (!allowed((Drives *)c, "fmi2CompletedIntegratorStep", IN(MODE_CONTINUOUS))) return fmi2Error;
    return check_current((Drives *)c);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    if (!allowed((Drives *)c, "fmi2SetTime", IN(MODE_EVENT) | IN(MODE_CONTINUOUS))) return fmi2Error;
    ((Drives *)c)->time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Drives *d = (Drives *)c;
    size_t k;
    if (!allowed(d, "fmi2SetContinuousStates", IN(MODE_CONTINUOUS))) return fmi2Error;
    if (nx != N_STATES) return fail(d, "%s", "fmi2SetContinuousStates: this FMU has 6 continuous states");
    for (k = 0; k < nx; k++) d->r[drives_state_vr[k]] = x[k];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    Drives *d = (Drives *)c;
    size_t k;
    if (!allowed(d, "fmi2GetDerivatives", IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_TERMINATED))) return fmi2Error;
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
    if (!allowed(d, "fmi2GetContinuousStates", IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_TERMINATED))) return fmi2Error;
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
    if (!allowed(d, "fmi2DoStep", IN(MODE_STEP))) return fmi2Error;
    if (h < 0.0) return fail(d, "%s", "fmi2DoStep: negative communication step");
    drives_advance(d->r, h);
    d->time = t + h;
    return check_current(d);
}
