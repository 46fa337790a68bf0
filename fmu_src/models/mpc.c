/*
 * The MpcController component in C: the native twin of crane_fmu/model/mpc.py, registered as a component
 * (component.h). Its variables and parameter rules come from MpcController_variables.h, generated from
 * mpc.VARIABLES; the MPC itself is mpc_axis.c's (the planar MPC of one axis, shared with the MpcController3D).
 */
#include "MpcController_variables.h"
#include "mpc_axis.h"

typedef MpcConfig Config;
typedef MpcState State;

#define V(name) (values[VR_##name])

/* mpc.configure(), after its RULES (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    MpcSettings s = {V(m1), V(m2), V(l1), V(l2), V(g), {0}, V(r), V(x_d), V(u_max), V(v_max), V(margin), V(h),
                     V(interval), V(horizon), V(max_iterations), V(replan_x), V(replan_angle), V(l1_low),
                     V(l1_high), V(identify), V(offset_free), V(estimated)};
    for (int i = 0; i < N_STATE; i++) s.q[i] = values[VR_q_x + i];
    return mpc_axis_configure(&s, c, r);
}

static void initial_state(const double values[], const Config *c, State *s) { mpc_axis_initial_state(s); }

/* mpc._output(): the inputs x .. dtheta2, l1_now, F2_hat, F1_hat are contiguous in the table. */
_Static_assert(VR_l1_now == VR_x + N_STATE && VR_F2_hat == VR_l1_now + 1 && VR_F1_hat == VR_F2_hat + 1,
               "MpcController's measured inputs and forces are contiguous");
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    return mpc_axis_outputs(c, s, &values[VR_x], out, r);
}

static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    return mpc_axis_update(c, s, &values[VR_x], "", r);
}

STATEFUL_COMPONENT;
