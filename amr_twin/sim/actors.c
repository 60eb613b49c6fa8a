/* The actors' motion on the loop's grid: each actor's pose at an instant, written to its mocap body.
 *
 * The C twin of ActorMotion.update_python (amr_twin/sim/actors.py) and ActorPath.pose_at
 * (amr_twin/model/actor_paths.py): the same operations in the same order on IEEE doubles
 * (compiled with -ffp-contract=off; fmod, sqrt, cos and sin from the same libm), so both give the
 * same bits; tests/sim/test_actors.py runs the grid with each. Part of the physics layer: it
 * writes MjData's mocap_pos and mocap_quat and reads the robot base's pose. The state lives in
 * the structs, which the Python class reads and writes too.
 * Built at first use against the installed MuJoCo's headers (amr_twin/sim/native_build.py).
 */
#include <math.h>
#include <stdint.h>
#include <mujoco/mujoco.h>
#include "c_layout.h"

typedef struct {
    const double* phases;   /* (nphase, 7): t0_s, x0_m, y0_m, vx_m_s, vy_m_s, yaw0_rad, yaw_rate_rad_s */
    int nphase;
    int mocap;              /* the actor's mocap index */
    double period_s;        /* the loop's period, 0 without a loop */
    int64_t start_us;       /* it sets off at this instant */
    int64_t progress_us;    /* walking time so far, us */
    int64_t last_us;        /* the instant of the last update */
    double stop_m;          /* halts while the robot is this near ahead; 0: never */
    double pose[3];         /* x_m, y_m, yaw_rad written last */
} actor_state;

typedef struct {
    int n;
    actor_state* a;
    int base_body;          /* the robot's base_link */
    double half_len_m, half_wid_m;  /* the robot's footprint about the base's origin (wheels included) */
} actors_ctx;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(actor_state), AMR_FIELD(actor_state, phases), AMR_FIELD(actor_state, nphase),
           AMR_FIELD(actor_state, mocap), AMR_FIELD(actor_state, period_s), AMR_FIELD(actor_state, start_us),
           AMR_FIELD(actor_state, progress_us), AMR_FIELD(actor_state, last_us),
           AMR_FIELD(actor_state, stop_m), AMR_FIELD(actor_state, pose), AMR_STRUCT(actors_ctx),
           AMR_FIELD(actors_ctx, n), AMR_FIELD(actors_ctx, a), AMR_FIELD(actors_ctx, base_body),
           AMR_FIELD(actors_ctx, half_len_m), AMR_FIELD(actors_ctx, half_wid_m))

/* The pose after t seconds of walking (ActorPath.pose_at). */
static void actor_pose(const actor_state* a, double t, double* out) {
    if (a->period_s > 0.0) t = fmod(t, a->period_s);
    int j = 0;
    while (j + 1 < a->nphase && a->phases[7 * (j + 1)] <= t) j++;
    const double* p = a->phases + 7 * j;
    double dt = t - p[0];
    out[0] = p[1] + dt * p[3];
    out[1] = p[2] + dt * p[4];
    out[2] = p[5] + dt * p[6];
}

/* Whether the robot's footprint is nearer than stop_m ahead of the actor (at its last pose). */
static int actor_blocked(const actors_ctx* c, const mjData* d, const actor_state* a) {
    if (a->stop_m <= 0.0) return 0;
    const double* p = d->xpos + 3 * c->base_body;
    const double* r = d->xmat + 9 * c->base_body;
    double hx = r[0], hy = r[3];
    double n = sqrt(hx * hx + hy * hy);
    double cs = hx / n, sn = hy / n;
    double dx = a->pose[0] - p[0], dy = a->pose[1] - p[1];
    double lx = cs * dx + sn * dy, ly = cs * dy - sn * dx;  /* the actor in the robot's frame */
    double qx = lx < -c->half_len_m ? -c->half_len_m : (lx > c->half_len_m ? c->half_len_m : lx);
    double qy = ly < -c->half_wid_m ? -c->half_wid_m : (ly > c->half_wid_m ? c->half_wid_m : ly);
    double gx = qx - lx, gy = qy - ly;  /* to the footprint's nearest point */
    double dist2 = gx * gx + gy * gy;
    if (dist2 >= a->stop_m * a->stop_m) return 0;
    double wx = cs * gx - sn * gy, wy = sn * gx + cs * gy;
    return wx * cos(a->pose[2]) + wy * sin(a->pose[2]) > 0.0 || dist2 == 0.0;
}

/* Grid instant t_us: advance each actor's walking time (unless it waits for the robot), pose it. */
void actors_update(actors_ctx* c, mjData* d, int64_t t_us) {
    for (int i = 0; i < c->n; i++) {
        actor_state* a = c->a + i;
        int64_t from = a->last_us > a->start_us ? a->last_us : a->start_us;
        if (t_us > from && !actor_blocked(c, d, a)) a->progress_us += t_us - from;
        a->last_us = t_us;
        actor_pose(a, (double)a->progress_us / 1e6, a->pose);
        double* mp = d->mocap_pos + 3 * a->mocap;
        double* mq = d->mocap_quat + 4 * a->mocap;
        double h = 0.5 * a->pose[2];
        mp[0] = a->pose[0];
        mp[1] = a->pose[1];
        mp[2] = 0.0;
        mq[0] = cos(h);
        mq[1] = 0.0;
        mq[2] = 0.0;
        mq[3] = sin(h);
    }
}

/* A row keeper's values: x_m, y_m, yaw_rad of each actor as last posed. */
void actors_row(const actors_ctx* c, const void* unused1, const void* unused2, double* row) {
    (void)unused1;
    (void)unused2;
    for (int i = 0; i < c->n; i++)
        for (int k = 0; k < 3; k++)
            row[3 * i + k] = c->a[i].pose[k];
}
