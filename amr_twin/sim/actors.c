/* The actors' motion on the loop's grid: each actor's pose at an instant, written to its mocap body.
 * An actor never walks into the robot: its step is cut where its geoms would press into the robot's
 * by more than touch_m (MuJoCo's mj_geomDistance between their geoms, as they stand).
 *
 * The C twin of ActorMotion.update_python (amr_twin/sim/actors.py) and ActorPath.pose_at
 * (amr_twin/model/actor_paths.py): the same operations in the same order on IEEE doubles
 * (compiled with -ffp-contract=off; fmod, sqrt, cos and sin from the same libm), so both give the
 * same bits; tests/sim/test_actors.py runs the grid with each. Part of the physics layer: it
 * writes MjData's mocap_pos and mocap_quat and reads the robot base's pose. The state lives in
 * the structs, which the Python class reads and writes too.
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
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
    const int* geoms;       /* its geoms that collide with the robot's (at most ACTOR_GEOMS) */
    const double* local;    /* (ngeom, 12): each one's position and rotation matrix in the actor's frame */
    int ngeom;
    double reach_m;         /* their farthest point from its origin in the floor's plane */
    int64_t give_way_us;    /* it walks on after giving way this long */
    int64_t waited_us;      /* how long it has given way (reset once the robot is out of its way) */
    int64_t held_us;        /* walking time lost to touching the robot, in all */
    double touch_m;         /* it presses into the robot this far at most */
    int touching;           /* it stopped against the robot and waits for a free step */
} actor_state;

#define ACTOR_GEOMS 8
#define BISECTIONS 12

typedef mjtNum (*geom_distance_fn)(const mjModel* m, mjData* d, int geom1, int geom2, mjtNum distmax,
                                   mjtNum fromto[6]);

typedef struct {
    int n;
    actor_state* a;
    int base_body;          /* the robot's base_link */
    double half_len_m, half_wid_m;  /* the robot's footprint about the base's origin (wheels included) */
    const mjModel* m;
    geom_distance_fn distance;      /* MuJoCo's mj_geomDistance */
    const int* robot_geoms;         /* the robot's colliding geoms */
    int nrobot;
    double robot_reach_m;           /* their farthest point from the base's origin in the floor's plane */
} actors_ctx;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(actor_state), AMR_FIELD(actor_state, phases), AMR_FIELD(actor_state, nphase),
           AMR_FIELD(actor_state, mocap), AMR_FIELD(actor_state, period_s), AMR_FIELD(actor_state, start_us),
           AMR_FIELD(actor_state, progress_us), AMR_FIELD(actor_state, last_us),
           AMR_FIELD(actor_state, stop_m), AMR_FIELD(actor_state, pose), AMR_FIELD(actor_state, geoms),
           AMR_FIELD(actor_state, local),           AMR_FIELD(actor_state, ngeom), AMR_FIELD(actor_state, reach_m), AMR_FIELD(actor_state, give_way_us),
           AMR_FIELD(actor_state, waited_us), AMR_FIELD(actor_state, held_us), AMR_FIELD(actor_state, touch_m),
           AMR_FIELD(actor_state, touching),           AMR_STRUCT(actors_ctx),
           AMR_FIELD(actors_ctx, n), AMR_FIELD(actors_ctx, a), AMR_FIELD(actors_ctx, base_body),
           AMR_FIELD(actors_ctx, half_len_m), AMR_FIELD(actors_ctx, half_wid_m), AMR_FIELD(actors_ctx, m),
           AMR_FIELD(actors_ctx, distance), AMR_FIELD(actors_ctx, robot_geoms), AMR_FIELD(actors_ctx, nrobot),
           AMR_FIELD(actors_ctx, robot_reach_m))

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

/* Put the actor's geoms (MjData's geom_xpos and geom_xmat) where they stand with the actor at pose. */
static void place_geoms(mjData* d, const actor_state* a, const double* pose) {
    double cs = cos(pose[2]), sn = sin(pose[2]);
    for (int i = 0; i < a->ngeom; i++) {
        const double* l = a->local + 12 * i;
        double* x = d->geom_xpos + 3 * a->geoms[i];
        double* r = d->geom_xmat + 9 * a->geoms[i];
        x[0] = pose[0] + (cs * l[0] - sn * l[1]);
        x[1] = pose[1] + (sn * l[0] + cs * l[1]);
        x[2] = l[2];
        for (int j = 0; j < 3; j++) {
            r[j] = cs * l[3 + j] - sn * l[6 + j];
            r[3 + j] = sn * l[3 + j] + cs * l[6 + j];
            r[6 + j] = l[9 + j];
        }
    }
}

/* The least signed distance from the actor's geoms to the robot's, where they stand (up to cutoff). */
static double robot_gap(const actors_ctx* c, mjData* d, const actor_state* a, double cutoff) {
    double gap = cutoff;
    for (int i = 0; i < a->ngeom; i++)
        for (int k = 0; k < c->nrobot; k++) {
            double g = c->distance(c->m, d, a->geoms[i], c->robot_geoms[k], cutoff, 0);
            if (g < gap) gap = g;
        }
    return gap;
}

/* The least signed distance to the robot with the actor after progress_us + dt_us of walking. */
static double gap_after(const actors_ctx* c, mjData* d, const actor_state* a, int64_t dt_us) {
    double pose[3];
    actor_pose(a, (double)(a->progress_us + dt_us) / 1e6, pose);
    place_geoms(d, a, pose);
    return robot_gap(c, d, a, 0.01);
}

/* The walking time (us, at most dt) the actor adds without pressing into the robot by more than
 * touch_m: all of dt when its geoms after the step are no deeper in the robot's; else the longest
 * share that is (bisection; it is then touching: it stops there, and walks on once a whole step is
 * free of the robot). The geoms are put back where they stand. */
static int64_t actor_step(const actors_ctx* c, mjData* d, actor_state* a, int64_t dt) {
    double next[3];
    actor_pose(a, (double)(a->progress_us + dt) / 1e6, next);
    double mx = next[0] - a->pose[0], my = next[1] - a->pose[1];
    const double* p = d->xpos + 3 * c->base_body;
    double bx = a->pose[0] - p[0], by = a->pose[1] - p[1];
    double reach = a->reach_m + c->robot_reach_m + sqrt(mx * mx + my * my) + 0.01;
    if (a->ngeom > ACTOR_GEOMS || bx * bx + by * by > reach * reach) {
        a->touching = 0;
        return dt;
    }
    double keep[12 * ACTOR_GEOMS];
    for (int i = 0; i < a->ngeom; i++) {
        for (int k = 0; k < 3; k++) keep[12 * i + k] = d->geom_xpos[3 * a->geoms[i] + k];
        for (int k = 0; k < 9; k++) keep[12 * i + 3 + k] = d->geom_xmat[9 * a->geoms[i] + k];
    }
    double gap = gap_after(c, d, a, dt);
    int64_t step = dt;
    if (a->touching) {
        if (gap < 0.0) step = 0;
        else a->touching = 0;
    } else if (gap < -a->touch_m) {
        a->touching = 1;
        int64_t lo = 0, hi = dt;
        for (int k = 0; k < BISECTIONS && hi - lo > 1; k++) {
            int64_t mid = lo + (hi - lo) / 2;
            if (gap_after(c, d, a, mid) >= -a->touch_m) lo = mid;
            else hi = mid;
        }
        step = lo;
    }
    for (int i = 0; i < a->ngeom; i++) {
        for (int k = 0; k < 3; k++) d->geom_xpos[3 * a->geoms[i] + k] = keep[12 * i + k];
        for (int k = 0; k < 9; k++) d->geom_xmat[9 * a->geoms[i] + k] = keep[12 * i + 3 + k];
    }
    return step;
}

/* Grid instant t_us: advance each actor's walking time (unless it gives way to the robot, for at most
 * give_way_us at a time, or touches it), pose it. */
void actors_update(actors_ctx* c, mjData* d, int64_t t_us) {
    for (int i = 0; i < c->n; i++) {
        actor_state* a = c->a + i;
        int64_t from = a->last_us > a->start_us ? a->last_us : a->start_us;
        if (t_us > from) {
            int64_t dt = t_us - from;
            if (!actor_blocked(c, d, a)) {
                a->waited_us = 0;
            } else if (a->waited_us < a->give_way_us) {
                a->waited_us += dt;
                dt = 0;
            }
            if (dt > 0) {
                int64_t step = actor_step(c, d, a, dt);
                a->held_us += dt - step;
                a->progress_us += step;
            }
        }
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
