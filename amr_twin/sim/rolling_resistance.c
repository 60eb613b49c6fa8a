/* Load-dependent rolling resistance of the tyres and ball casters, one grid instant.
 *
 * The C twin of RollingResistance.__call__ (amr_twin/sim/rolling_resistance.py): the same
 * operations in the same order on IEEE doubles (compiled with -ffp-contract=off), so that
 * both give the same bits; tests/sim/test_rolling_resistance.py checks a run of each.
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <mujoco/mujoco.h>
#include "c_layout.h"

typedef struct {
    int tyre_qpos[2], tyre_dof[2];      /* tyre slide joints: qpos and dof addresses */
    int caster_qpos[4], caster_dof[4];  /* caster slide joints */
    int ball_body[4];                   /* ball bodies (their xpos) */
    int base, root_dof, wheel_dof[2];   /* chassis body, its free joint's first dof, wheel hinges */
    int ngeom;
    const int* support_of_geom;         /* (ngeom,) support index 0-5 of each geom, -1 for the others */
    double k_t, c_t;                    /* tyre stiffness N/m, damping N s/m */
    double f0_c, k_c, c_c;              /* caster preload plus ball weight N, stiffness N/m, damping N s/m */
    double tyre_arm_m;                  /* Crr r, m */
    double motor_friction[2];           /* the hinges' own friction loss, N m */
    double ball_crr;                    /* caster Crr */
    double ball_speed_eps;              /* m/s */
} rr_params;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(rr_params), AMR_FIELD(rr_params, tyre_qpos), AMR_FIELD(rr_params, tyre_dof),
           AMR_FIELD(rr_params, caster_qpos), AMR_FIELD(rr_params, caster_dof),
           AMR_FIELD(rr_params, ball_body), AMR_FIELD(rr_params, base), AMR_FIELD(rr_params, root_dof),
           AMR_FIELD(rr_params, wheel_dof), AMR_FIELD(rr_params, ngeom),
           AMR_FIELD(rr_params, support_of_geom), AMR_FIELD(rr_params, k_t), AMR_FIELD(rr_params, c_t),
           AMR_FIELD(rr_params, f0_c), AMR_FIELD(rr_params, k_c), AMR_FIELD(rr_params, c_c),
           AMR_FIELD(rr_params, tyre_arm_m), AMR_FIELD(rr_params, motor_friction),
           AMR_FIELD(rr_params, ball_crr), AMR_FIELD(rr_params, ball_speed_eps))

/* Normal contact force (6,) N on the wheels L, R and caster balls fl, fr, rl, rr in the last
 * step: each contact's first constraint row, summed by support in contact order, as
 * Physics.support_normal_forces_n (amr_twin/sim/physics.py) does in Python. */
void rr_contact_loads(const mjData* d, const rr_params* p, double* out) {
    for (int k = 0; k < 6; k++)
        out[k] = 0.0;
    for (int i = 0; i < d->ncon; i++) {
        const mjContact* con = d->contact + i;
        int g1 = con->geom[0], g2 = con->geom[1];
        int k1 = (g1 >= 0 && g1 < p->ngeom) ? p->support_of_geom[g1] : -1;
        int k2 = (g2 >= 0 && g2 < p->ngeom) ? p->support_of_geom[g2] : -1;
        int k = k1 > k2 ? k1 : k2;
        if (k >= 0 && con->efc_address >= 0)
            out[k] += d->efc_force[con->efc_address];
    }
}

/* Normal loads (6,) N: wheel left, right, casters fl, fr, rl, rr; sets the hinges' friction
 * loss and the chassis' generalized force (unless ball_crr is 0). */
void rr_update(const mjModel* m, mjData* d, const rr_params* p, double* loads) {
    const double* qpos = d->qpos;
    const double* qvel = d->qvel;
    double load, contact[6];
    int have_contact = 0;

    for (int w = 0; w < 2; w++) {
        load = p->k_t * qpos[p->tyre_qpos[w]] + p->c_t * qvel[p->tyre_dof[w]];
        loads[w] = load > 0.0 ? load : 0.0;
    }
    for (int c = 0; c < 4; c++) {
        double q = qpos[p->caster_qpos[c]];
        if (q > 1e-6) {  /* off its stop: the spring carries the load */
            load = p->f0_c + p->k_c * q + p->c_c * qvel[p->caster_dof[c]];
            loads[2 + c] = load > 0.0 ? load : 0.0;
        } else {  /* on its stop (or lifted): the contact force of the last step */
            if (!have_contact) {
                rr_contact_loads(d, p, contact);
                have_contact = 1;
            }
            loads[2 + c] = contact[2 + c];
        }
    }
    m->dof_frictionloss[p->wheel_dof[0]] = p->motor_friction[0] + p->tyre_arm_m * loads[0];
    m->dof_frictionloss[p->wheel_dof[1]] = p->motor_friction[1] + p->tyre_arm_m * loads[1];
    if (p->ball_crr == 0.0)
        return;
    int r0 = p->root_dof;
    const double* xm = d->xmat + 9 * p->base;
    double x6 = xm[6], x7 = xm[7], x8 = xm[8];
    double vx = qvel[r0], vy = qvel[r0 + 1];
    double wz = x6 * qvel[r0 + 3] + x7 * qvel[r0 + 4] + x8 * qvel[r0 + 5];
    double bx = d->xpos[3 * p->base], by = d->xpos[3 * p->base + 1];
    double fx = 0.0, fy = 0.0, tz = 0.0;
    for (int c = 0; c < 4; c++) {
        const double* pb = d->xpos + 3 * p->ball_body[c];
        double rx = pb[0] - bx, ry = pb[1] - by;
        double ux = vx - wz * ry, uy = vy + wz * rx;
        double speed = sqrt(ux * ux + uy * uy);
        double scale = p->ball_crr * loads[2 + c] / (p->ball_speed_eps > speed ? p->ball_speed_eps : speed);
        double fx_i = -scale * ux, fy_i = -scale * uy;
        fx = fx + fx_i;
        fy = fy + fy_i;
        tz = tz + rx * fy_i - ry * fx_i;
    }
    double* qfrc = d->qfrc_applied + r0;
    qfrc[0] = fx;
    qfrc[1] = fy;
    qfrc[2] = 0.0;
    qfrc[3] = x6 * tz;
    qfrc[4] = x7 * tz;
    qfrc[5] = x8 * tz;
}

/* A row (19,) of a sweep point's support sample, as RollingResistance.support_rows keeps it in
 * Python: the loads of the last update (6), the contact loads (6, rr_contact_loads), the
 * world z of the base's z axis and the base's free-joint velocity (6). */
void rr_support_row(const mjData* d, const rr_params* p, const double* loads, double* row) {
    for (int k = 0; k < 6; k++)
        row[k] = loads[k];
    rr_contact_loads(d, p, row + 6);
    row[12] = d->xmat[9 * p->base + 8];
    for (int k = 0; k < 6; k++)
        row[13 + k] = d->qvel[p->root_dof + k];
}
