/*
 * The planar MPC of one axis in C (crane_fmu/model/mpc.py: its configure(), the tracking designs, the plan by
 * bisection, the tracking QP with its warm start and its iteration cap, the identification, the plans made again
 * and the hand-over to the LQR), apart from any variable table: the MpcController (mpc.c) runs one, the
 * MpcController3D (mpc3d.c) one per axis. The QPs are solved by qp.c, the C of qp.py; the designs are made by
 * lqr_design.c and linalg.c in mpc.py's order of operations.
 *
 * The state is mpc.py's tuple as a flat array in its layout (the header, the last solution, its active rows, the
 * plan's inputs and states). The MpcConfig holds the designs (fixed-size, so that an FMU state is a plain copy of
 * the model) and, as mpc.py's Config.memo, the identified model's design and the last solve, which the outputs and
 * the step share. The plan's QPs (their size is the move's) are made in memory of their own, freed after the plan.
 */
#ifndef MPC_AXIS_H
#define MPC_AXIS_H

#include "component.h"
#include "lqr_design.h"
#include "qp.h"

#define RHO 1e6          /* mpc.RHO */
#define REACHED 1e-3     /* mpc.REACHED */
#define LONGEST_PLAN 6.0 /* mpc.LONGEST_PLAN */
#define REPLAN_GAP 0.25  /* mpc.REPLAN_GAP */
#define RETRY_GAP 6.0    /* mpc.RETRY_GAP */
#define LARGEST_SWING (17.5 * (3.141592653589793 / 180.0)) /* mpc.LARGEST_SWING: math.radians(17.5) */
#define PLAN_BELOW (16.0 * (3.141592653589793 / 180.0))     /* mpc.PLAN_BELOW: math.radians(16.0) */
#define WELL_POSED 1e-2  /* mpc.WELL_POSED */
#define MISFIT 1e-5      /* mpc.MISFIT */
#define PLAUSIBLE 2.0    /* mpc.PLAUSIBLE */
#define PLAUSIBLE_PAYLOAD 3.0 /* mpc.PLAUSIBLE_PAYLOAD */
#define STANDARD_ERROR 0.01   /* mpc.STANDARD_ERROR */
#define UNEXPLAINED 1e-3      /* mpc.UNEXPLAINED */
#define MOST_REPLANS 2.0      /* mpc.MOST_REPLANS */
#define SWING_MARGIN (10.0 * (3.141592653589793 / 180.0)) /* mpc.SWING_MARGIN: math.radians(10.0) */
#define TOLERANCE 0.01   /* mpc.TOLERANCE */
#define SUSPECT_AFTER 3.0 /* mpc.SUSPECT_AFTER */
#define CAUTIOUS_STRETCH 1.3 /* mpc.CAUTIOUS_STRETCH */
#define PEAK_ALLOWANCE (1.0 * (3.141592653589793 / 180.0)) /* mpc.PEAK_ALLOWANCE: math.radians(1.0) */
#define N_PEAK_STRETCHES 6 /* mpc.PEAK_STRETCHES: their values in mpc_axis.c */
#define SPREAD_L1 0.1        /* mpc.SPREAD: l1, l2, m1, m2 */
#define SPREAD_L2 0.2
#define SPREAD_M1 0.2
#define SPREAD_M2 0.5
/* SCHEDULE_POINTS, MAX_STEPS (the horizon's rule), MAX_PLAN (mpc.MAX_PLAN: the interval's rule) */
enum { SCHEDULE_POINTS = 11, MAX_STEPS = 200, MAX_ROWS = 2 * MAX_STEPS, MAX_PLAN = 1200 };
enum { N_CORNERS = 16 }; /* mpc.robust_ends(): the corners of mpc.SPREAD */
#define N_ROBUST_WEIGHTS 5 /* mpc.ROBUST_WEIGHTS: their values in mpc_axis.c */
/* the measured inputs of one axis: x .. dtheta2, l1_now, then the estimated forces F2_hat, F1_hat */
enum { N_INPUTS = N_STATE + 3 };

/* mpc.HEADER */
enum {
    H_COUNT, H_U, H_ITERATIONS, H_WARNED, H_PLAN_STEPS, H_PLAN_START, H_PLAN_AFTER, H_PLAN_L1, H_L1, H_L2, H_M2,
    H_W1, H_W2, H_COS_D, H_SIN_D, H_COS1, H_SIN1, H_COS2, H_SIN2, H_D1, H_D2, H_A1, H_A2, H_C1, H_C2, H_S1, H_S2,
    H_N11, H_N12, H_N13, H_N22, H_N23, H_N33, H_Z1, H_Z2, H_Z3, H_YY, H_SAMPLES, H_HANDED, H_REPLANS, H_BOUND,
    H_CAUTIOUS, H_HIT, H_FIRST, H_N_HEADER
};
enum { STATE_SIZE = H_N_HEADER + 3 * MAX_STEPS + MAX_PLAN + N_STATE * (MAX_PLAN + 1) };

/* mpc.Design: the tracking QP for one model, prepared (qp.prepare) over the Config's constraint rows. */
typedef struct {
    double l1, ad[N_STATE][N_STATE], bd[N_STATE], omegas[2], shapes[2][2];
    double gain[MAX_STEPS][N_STATE];
    double hinv[MAX_STEPS * MAX_STEPS], g[MAX_ROWS * MAX_STEPS], norms[MAX_ROWS];
    int chain_end[MAX_ROWS];
} Design;

typedef struct {
    double v[STATE_SIZE];
} MpcState;

/* mpc.Config, with memo's parts and the scratch of the solves and designs. */
typedef struct {
    Design designs[SCHEDULE_POINTS + 1]; /* the schedule's (or the one), then the identified model's */
    int n_designs, have_identified;
    double identified[3]; /* the identified model (l1, l2, m2) its design is for */
    /* mpc.robust_ends() (memo "corners"): the corners' (Ad, Bd, fast_mode_rows) about the model corners_for */
    int have_corners;
    double corners_for[3], corner_ad[N_CORNERS][N_STATE][N_STATE], corner_bd[N_CORNERS][N_STATE];
    double corner_rows[N_CORNERS][2][N_STATE];
    PlantParameters plant;
    double weights[N_STATE], r, x_d, u_max, v_max, margin, h, every, interval, replan_x, replan_angle;
    int steps, max_iterations, samples;
    double lqr_gains[N_STATE], lqr_table[SCHEDULE_POINTS][N_STATE]; /* mpc.Config.lqr: the LQR it hands over to */
    double offset_free; /* mpc.Config.lqr.offset_free: the forces' rest off the QP's error and the LQR's target */
    double estimated;   /* mpc.Config.estimated: the data unexplained beyond MISFIT (else UNEXPLAINED) */
    int first[MAX_ROWS], length[MAX_ROWS], offset[MAX_ROWS]; /* mpc.constraint_rows() */
    double values[1 + MAX_STEPS];
    double work[QP_WORK(MAX_STEPS, MAX_ROWS)], scratch[3 * MAX_STEPS * MAX_STEPS + 7 * MAX_STEPS * N_STATE];
    int iwork[QP_IWORK(MAX_ROWS)], hint_rows[MAX_ROWS], hint_sides[MAX_ROWS], active[MAX_ROWS], sides[MAX_ROWS];
    int memo_valid, memo_warns; /* the last solve: its state and inputs, the new state, whether it warns */
    double memo_inputs[N_INPUTS]; /* x .. dtheta2, l1_now, F2_hat, F1_hat */
    MpcState memo_state, memo_next;
} MpcConfig;

/* mpc.configure()'s parameters (mpc.VARIABLES' parameters, by name). */
typedef struct {
    double m1, m2, l1, l2, g, q[N_STATE], r, x_d, u_max, v_max, margin, h, interval, horizon, max_iterations;
    double replan_x, replan_angle, l1_low, l1_high, identify, offset_free, estimated;
} MpcSettings;

/* mpc.configure(), after its declared RULES: the rules that need the interval and the horizon counted in steps,
   then the designs. */
/* planner.shortest_steps()'s plan (the TrajectoryPlanner's shaper "shortest"): mpc.plan_move on (ad, bd) from the swing
   start (theta1, dtheta1, theta2, dtheta2) at 0 to rest at distance; its inputs into plan_u (MAX_PLAN of room), their number into *n_plan. */
const char *mpc_axis_plan_rest_to_rest(const double ad[N_STATE][N_STATE], const double bd[N_STATE], double distance,
                                       const double start[4], double u_max, double v_max, double interval,
                                       double stretch, double *plan_u, int *n_plan);
ModelStatus mpc_axis_configure(const MpcSettings *v, MpcConfig *c, const Reporter *r);

/* mpc.initial_state(): zeros. */
void mpc_axis_initial_state(MpcState *s);

/* mpc._output(): u, the QP's iterations and the plan's end, from the inputs (x .. dtheta2, l1_now, F2_hat, F1_hat). */
ModelStatus mpc_axis_outputs(const MpcConfig *c, const MpcState *s, const double inputs[N_INPUTS], double out[3],
                             const Reporter *r);

/* mpc.update(): one step; the iteration cap's warning (once) begins with `prefix`. */
ModelStatus mpc_axis_update(const MpcConfig *c, MpcState *s, const double inputs[N_INPUTS], const char *prefix,
                            const Reporter *r);

#endif
