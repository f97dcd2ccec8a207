/* The three joint drives of the EjsRL paper's figure 13, as equations shared by the
 * FMI glue: per joint j, a PID controller on the position error (derivative on the
 * measured velocity), a power amplifier with a gain and a saturation, and a DC motor's
 * armature circuit behind a gearbox.
 *
 *   e_j   = q_ref_j - q_j
 *   u_j   = Kp e_j + Ki ei_j - Kd qd_j              controller output (V)
 *   V_j   = clip(Ka u_j, -V_max, V_max)             amplifier output (V)
 *   di_j  = (V_j - R i_j - Kb G_j qd_j) / La        armature current (A/s)
 *   dei_j = e_j (1 - saturated_j)                   integral of the error, anti-windup
 *   tau_j = G_j Kt i_j                              joint torque (N m)
 *
 * The variables are one array of doubles indexed by value reference (VR_...).
 */
#ifndef DRIVES_H
#define DRIVES_H

#include <math.h>

#define N_JOINTS 3
/* inputs */
#define VR_Q_REF 0   /* q_ref1..3 (rad) */
#define VR_Q 3       /* q1..3 (rad) */
#define VR_QD 6      /* qd1..3 (rad/s) */
/* outputs */
#define VR_TAU 9     /* tau1..3 (N m) */
#define VR_V 12      /* V1..3 (V) */
/* continuous states and their derivatives */
#define VR_I 15      /* i1..3 (A) */
#define VR_EI 18     /* ei1..3 (rad s) */
#define VR_DER_I 21
#define VR_DER_EI 24
/* parameters */
#define VR_KP 27
#define VR_KI 28
#define VR_KD 29
#define VR_KA 30
#define VR_VMAX 31
#define VR_R 32
#define VR_LA 33
#define VR_KT 34
#define VR_KB 35
#define VR_G 36      /* G1..3 */
#define VR_IMAX 39
#define N_VARS 40
#define N_STATES 6

/* the start values, by value reference (as in modelDescription.xml) */
static void drives_defaults(double *r) {
    int k;
    for (k = 0; k < N_VARS; k++) r[k] = 0.0;
    r[VR_KP] = 12.0; r[VR_KI] = 10.0; r[VR_KD] = 0.4; r[VR_KA] = 10.0; r[VR_VMAX] = 48.0;
    r[VR_R] = 1.0; r[VR_LA] = 0.005; r[VR_KT] = 0.02; r[VR_KB] = 0.02;
    r[VR_G] = 100.0; r[VR_G + 1] = 100.0; r[VR_G + 2] = 50.0; r[VR_IMAX] = 1000.0;
}

/* outputs and state derivatives from the inputs, states and parameters */
static void drives_compute(double *r) {
    int j;
    for (j = 0; j < N_JOINTS; j++) {
        double e = r[VR_Q_REF + j] - r[VR_Q + j];
        double u = r[VR_KP] * e + r[VR_KI] * r[VR_EI + j] - r[VR_KD] * r[VR_QD + j];
        double vu = r[VR_KA] * u;
        double vmax = r[VR_VMAX];
        double v = vu < -vmax ? -vmax : (vu > vmax ? vmax : vu);
        double saturated = fabs(vu) >= vmax ? 1.0 : 0.0;
        double g = r[VR_G + j];
        r[VR_V + j] = v;
        r[VR_TAU + j] = g * r[VR_KT] * r[VR_I + j];
        r[VR_DER_I + j] = (v - r[VR_R] * r[VR_I + j] - r[VR_KB] * g * r[VR_QD + j]) / r[VR_LA];
        r[VR_DER_EI + j] = e * (1.0 - saturated);
    }
}

/* the continuous states in the order of the model structure: i1..3 then ei1..3 */
static const int drives_state_vr[N_STATES] = {VR_I, VR_I + 1, VR_I + 2, VR_EI, VR_EI + 1, VR_EI + 2};
static const int drives_der_vr[N_STATES] = {VR_DER_I, VR_DER_I + 1, VR_DER_I + 2, VR_DER_EI, VR_DER_EI + 1, VR_DER_EI + 2};

/* the joint whose armature current exceeds i_max (0-based), or -1 */
static int drives_overcurrent(const double *r) {
    int j;
    for (j = 0; j < N_JOINTS; j++) {
        if (fabs(r[VR_I + j]) > r[VR_IMAX]) return j;
    }
    return -1;
}

/* advance the states over h with the inputs held (co-simulation): RK4 in substeps of at most 1 ms */
static void drives_advance(double *r, double h) {
    int n = (int)ceil(h / 1e-3 - 1e-9), s, k;
    double dt, x0[N_STATES], k1[N_STATES], k2[N_STATES], k3[N_STATES], k4[N_STATES];
    if (n < 1) n = 1;
    dt = h / n;
    for (s = 0; s < n; s++) {
        for (k = 0; k < N_STATES; k++) x0[k] = r[drives_state_vr[k]];
        drives_compute(r);
        for (k = 0; k < N_STATES; k++) { k1[k] = r[drives_der_vr[k]]; r[drives_state_vr[k]] = x0[k] + 0.5 * dt * k1[k]; }
        drives_compute(r);
        for (k = 0; k < N_STATES; k++) { k2[k] = r[drives_der_vr[k]]; r[drives_state_vr[k]] = x0[k] + 0.5 * dt * k2[k]; }
        drives_compute(r);
        for (k = 0; k < N_STATES; k++) { k3[k] = r[drives_der_vr[k]]; r[drives_state_vr[k]] = x0[k] + dt * k3[k]; }
        drives_compute(r);
        for (k = 0; k < N_STATES; k++) { k4[k] = r[drives_der_vr[k]]; r[drives_state_vr[k]] = x0[k] + dt / 6.0 * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k]); }
    }
    drives_compute(r);
}

#endif
