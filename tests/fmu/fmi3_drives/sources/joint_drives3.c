/* FMI 3.0 glue of lab 8's joint drives (drives.h, copied beside this file by the tests):
 * the same equations as the lab's FMI 2.0 FMU, for testing ejsgen's FMI 3.0 path
 * (model exchange and co-simulation). A current above i_max logs why and returns fmi3Error, and
 * so does a call the FMI 3.0 state machine forbids in the FMU's state (as the Reference FMUs'
 * masks): a tunable parameter set in continuous-time mode, a fixed one or a start value after
 * initialization, setTime/setContinuousStates/completedIntegratorStep/updateDiscreteStates or
 * doStep in the wrong mode. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "drives.h"

#define TOKEN "{8c4e2f1a-6b3d-4e5f-9a0b-1c2d3e4f5a6b}"

typedef enum { MODE_INSTANTIATED, MODE_INIT, MODE_EVENT, MODE_CONTINUOUS, MODE_STEP, MODE_TERMINATED } Mode;
static const char *MODE_NAMES[] = {"the instantiated state", "initialization mode", "event mode", "continuous-time mode", "step mode", "the terminated state"};
#define IN(m) (1 << (m))

typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    char *name;
    int cs;
    Mode mode;
    double time;
    double r[N_VARS];
} Drives;

static fmi3Status say_error(Drives *d, const char *text) {
    if (d != NULL && d->log != NULL) d->log(d->env, fmi3Error, "logStatusError", text);
    return fmi3Error;
}

/* a call the FMU's state forbids: logged, fmi3Error */
static int allowed(Drives *d, const char *fn, int mask) {
    char text[160];
    if (d == NULL) return 0;
    if (mask & IN(d->mode)) return 1;
    snprintf(text, sizeof text, "%s: Illegal call sequence (the FMU is in %s)", fn, MODE_NAMES[d->mode]);
    say_error(d, text);
    return 0;
}

static int set_mask(fmi3ValueReference vr) {
    if (vr < VR_TAU) return IN(MODE_INSTANTIATED) | IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP);
    if (vr == VR_KP || vr == VR_KI || vr == VR_KD || vr == VR_KA || vr == VR_VMAX || vr == VR_IMAX)
        return IN(MODE_INSTANTIATED) | IN(MODE_INIT) | IN(MODE_EVENT) | IN(MODE_STEP);
    return IN(MODE_INSTANTIATED) | IN(MODE_INIT);
}

static fmi3Status unsupported(fmi3Instance instance, const char *what) {
    char text[128];
    snprintf(text, sizeof text, "%s is not supported", what);
    return say_error((Drives *)instance, text);
}

static fmi3Status check_current(Drives *d) {
    char text[256];
    int j = drives_overcurrent(d->r);
    if (j < 0) return fmi3OK;
    snprintf(text, sizeof text, "joint %d: armature current %.3g A exceeds the amplifier's limit i_max = %.3g A at t = %.4g s",
             j + 1, d->r[VR_I + j], d->r[VR_IMAX], d->time);
    return say_error(d, text);
}

static fmi3Instance make(fmi3String name, fmi3String token, fmi3InstanceEnvironment env, fmi3LogMessageCallback log, int cs) {
    Drives *d;
    if (token == NULL || strcmp(token, TOKEN) != 0) {
        if (log != NULL) log(env, fmi3Error, "logStatusError", "wrong instantiation token");
        return NULL;
    }
    d = (Drives *)calloc(1, sizeof(Drives));
    if (d == NULL) return NULL;
    d->env = env;
    d->log = log;
    d->name = (char *)malloc(strlen(name ? name : "") + 1);
    strcpy(d->name, name ? name : "");
    d->cs = cs;
    d->mode = MODE_INSTANTIATED;
    drives_defaults(d->r);
    drives_compute(d->r);
    return d;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String categories[]) {
    (void)instance; (void)on; (void)n; (void)categories;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback log) {
    (void)resources; (void)visible; (void)logging;
    return make(name, token, env, log, 0);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference required[], size_t nRequired, fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update) {
    (void)resources; (void)visible; (void)logging; (void)eventModeUsed; (void)earlyReturnAllowed; (void)required; (void)nRequired; (void)update;
    return make(name, token, env, log, 1);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                               fmi3Boolean logging, fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                               fmi3ClockUpdateCallback clock, fmi3LockPreemptionCallback lock,
                                               fmi3UnlockPreemptionCallback unlock) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)env; (void)log; (void)clock; (void)lock; (void)unlock;
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Drives *d = (Drives *)instance;
    if (d == NULL) return;
    free(d->name);
    free(d);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolDefined, fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stopDefined, fmi3Float64 stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    if (!allowed((Drives *)instance, "fmi3EnterInitializationMode", IN(MODE_INSTANTIATED))) return fmi3Error;
    ((Drives *)instance)->time = start;
    ((Drives *)instance)->mode = MODE_INIT;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Drives *d = (Drives *)instance;
    if (!allowed(d, "fmi3ExitInitializationMode", IN(MODE_INIT))) return fmi3Error;
    drives_compute(d->r);
    d->mode = d->cs ? MODE_STEP : MODE_EVENT;
    return check_current(d);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    if (!allowed((Drives *)instance, "fmi3EnterEventMode", IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP))) return fmi3Error;
    ((Drives *)instance)->mode = MODE_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    if (!allowed((Drives *)instance, "fmi3Terminate", IN(MODE_EVENT) | IN(MODE_CONTINUOUS) | IN(MODE_STEP))) return fmi3Error;
    ((Drives *)instance)->mode = MODE_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    Drives *d = (Drives *)instance;
    drives_defaults(d->r);
    drives_compute(d->r);
    d->time = 0.0;
    d->mode = MODE_INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[], size_t nValues) {
    Drives *d = (Drives *)instance;
    size_t k;
    (void)nValues;
    drives_compute(d->r);
    for (k = 0; k < nvr; k++) {
        if (vr[k] >= N_VARS) return say_error(d, "fmi3GetFloat64: unknown value reference");
        values[k] = d->r[vr[k]];
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[], size_t nValues) {
    Drives *d = (Drives *)instance;
    size_t k;
    (void)nValues;
    for (k = 0; k < nvr; k++) {
        if (vr[k] >= N_VARS) return say_error(d, "fmi3SetFloat64: unknown value reference");
        if (!allowed(d, "fmi3SetFloat64", set_mask(vr[k]))) return fmi3Error;
        d->r[vr[k]] = values[k];
    }
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *needUpdate, fmi3Boolean *terminate, fmi3Boolean *nominalsChanged,
                                    fmi3Boolean *valuesChanged, fmi3Boolean *nextDefined, fmi3Float64 *next) {
    if (!allowed((Drives *)instance, "fmi3UpdateDiscreteStates", IN(MODE_EVENT))) return fmi3Error;
    *needUpdate = fmi3False; *terminate = fmi3False; *nominalsChanged = fmi3False;
    *valuesChanged = fmi3False; *nextDefined = fmi3False; *next = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    if (!allowed((Drives *)instance, "fmi3EnterContinuousTimeMode", IN(MODE_EVENT))) return fmi3Error;
    ((Drives *)instance)->mode = MODE_CONTINUOUS;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    if (!allowed((Drives *)instance, "fmi3EnterStepMode", IN(MODE_EVENT))) return fmi3Error;
    ((Drives *)instance)->mode = MODE_STEP;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetPrior, fmi3Boolean *enterEventMode, fmi3Boolean *terminate) {
    (void)noSetPrior;
    *enterEventMode = fmi3False;
    *terminate = fmi3False;
    if (!allowed((Drives *)instance, "fmi3CompletedIntegratorStep", IN(MODE_CONTINUOUS))) return fmi3Error;
    return check_current((Drives *)instance);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    if (!allowed((Drives *)instance, "fmi3SetTime", IN(MODE_EVENT) | IN(MODE_CONTINUOUS))) return fmi3Error;
    ((Drives *)instance)->time = time;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx) {
    Drives *d = (Drives *)instance;
    size_t k;
    if (!allowed(d, "fmi3SetContinuousStates", IN(MODE_CONTINUOUS))) return fmi3Error;
    if (nx != N_STATES) return say_error(d, "fmi3SetContinuousStates: this FMU has 6 continuous states");
    for (k = 0; k < nx; k++) d->r[drives_state_vr[k]] = x[k];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t nx) {
    Drives *d = (Drives *)instance;
    size_t k;
    if (nx != N_STATES) return say_error(d, "fmi3GetContinuousStateDerivatives: this FMU has 6 continuous states");
    drives_compute(d->r);
    for (k = 0; k < nx; k++) dx[k] = d->r[drives_der_vr[k]];
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t nz) {
    (void)instance; (void)z;
    return nz == 0 ? fmi3OK : fmi3Error;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx) {
    Drives *d = (Drives *)instance;
    size_t k;
    if (nx != N_STATES) return say_error(d, "fmi3GetContinuousStates: this FMU has 6 continuous states");
    for (k = 0; k < nx; k++) x[k] = d->r[drives_state_vr[k]];
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx) {
    size_t k;
    (void)instance;
    for (k = 0; k < nx; k++) x[k] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) { (void)instance; *n = 0; return fmi3OK; }
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) { (void)instance; *n = N_STATES; return fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior, fmi3Boolean *eventNeeded,
                      fmi3Boolean *terminate, fmi3Boolean *earlyReturn, fmi3Float64 *lastTime) {
    Drives *d = (Drives *)instance;
    (void)noSetPrior;
    if (!allowed(d, "fmi3DoStep", IN(MODE_STEP))) return fmi3Error;
    drives_advance(d->r, h);
    d->time = t + h;
    *eventNeeded = fmi3False; *terminate = fmi3False; *earlyReturn = fmi3False; *lastTime = d->time;
    return check_current(d);
}

#include "unsupported3.inc"
