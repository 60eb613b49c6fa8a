/* Brush tyres with relaxation: the drive wheels' floor forces, every physics step (mjcb_passive).
 *
 * The C twin of tyre_forces in amr_twin/sim/tyres.py (the model, its symbols and its sources are
 * described there and in docs/explanation/tyres.md): the same operations in the same order on IEEE doubles
 * (compiled with -ffp-contract=off), so that both give the same bits; tests/sim/test_tyres.py runs
 * a twin with each. MuJoCo calls tyres_passive at the end of mj_passive in every mj_forward (so in
 * every mj_step); it acts on each robot whose numeric (TYRE_NUMERIC, or TYRE_NUMERIC":<prefix>" in
 * a fleet) amr_twin/model/build.py wrote (parameters and the addresses it needs), and keeps each
 * wheel's contact patch deflections in the robot's block of d->userdata (a copy of MjData carries
 * them). The state advances only when
 * d->time has moved on, so an extra mj_forward at the same instant changes nothing.
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <string.h>
#include <mujoco/mujoco.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define TYRE_NUMERIC "amr_tyres"
#define TYRE_FORMAT 1.0

/* numeric layout (doubles): see NUMERIC_FIELDS in tyres.py */
enum { N_FORMAT, N_USERDATA, N_ROOT_DOF, N_BASE, N_MU, N_C_ALPHA, N_C_KAPPA, N_SIGMA_ALPHA, N_SIGMA_KAPPA,
       N_CROWN, N_LOSS, N_K_T, N_C_T, N_V_SIGN, N_WHEEL0 };
enum { W_SLIDE, W_HINGE, W_GEOM, W_SIZE };
/* userdata layout: t_state, then per wheel u, v, psi (state) and fx, fy, mz, load (last output),
 * then the floor's friction field: node count n (0: none), node spacing, n x n coefficients (row y) */
enum { S_U, S_V, S_PSI, S_FX, S_FY, S_MZ, S_LOAD, S_SIZE };
enum { U_T, U_WHEEL0, U_FIELD = U_WHEEL0 + 2 * S_SIZE };

static void cross(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Whether numeric i is a robot's tyres: named TYRE_NUMERIC or TYRE_NUMERIC":<prefix>" (its names
 * read directly: the helper is not linked to libmujoco, whose symbols the bindings keep to
 * themselves). */
static int is_tyre_numeric(const mjModel* m, int i) {
    const char* name = m->names + m->name_numericadr[i];
    size_t n = strlen(TYRE_NUMERIC);
    return strncmp(name, TYRE_NUMERIC, n) == 0 && (name[n] == '\0' || name[n] == ':');
}

/* The floor's friction coefficient at (x, y), m: bilinear between the field's nodes, which repeat
 * every n nodes (its Python twin: friction_at in amr_twin/sim/floor_friction.py). */
static double friction_at(const double* f, double x, double y) {
    long n = (long)f[0];
    double cell = f[1];
    const double* v = f + 2;
    double u = x / cell, w = y / cell;
    double iu = floor(u), iw = floor(w);
    double fx = u - iu, fy = w - iw;
    long i0 = (((long)iu) % n + n) % n, j0 = (((long)iw) % n + n) % n;
    long i1 = (i0 + 1) % n, j1 = (j0 + 1) % n;
    double a = v[j0 * n + i0] + fx * (v[j0 * n + i1] - v[j0 * n + i0]);
    double b = v[j1 * n + i0] + fx * (v[j1 * n + i1] - v[j1 * n + i0]);
    return a + fy * (b - a);
}

static void robot_tyres(const mjModel* m, mjData* d, const double* p);

/* The passive callback: each robot's tyres, in numeric order (each adds to its own dofs). */
void tyres_passive(const mjModel* m, mjData* d) {
    for (int i = 0; i < m->nnumeric; i++)
        if (is_tyre_numeric(m, i))
            robot_tyres(m, d, m->numeric_data + m->numeric_adr[i]);
}

/* One robot's two tyres, from its numeric p. */
static void robot_tyres(const mjModel* m, mjData* d, const double* p) {
    if (p[N_FORMAT] != TYRE_FORMAT)
        return;
    double* st = d->userdata + (int)p[N_USERDATA];
    double t = d->time;
    double dt = t - st[U_T];
    if (!(dt > 0.0))  /* the same instant (or a clock set back): the state stays */
        dt = 0.0;
    st[U_T] = t;
    int r0 = (int)p[N_ROOT_DOF], base = (int)p[N_BASE];
    const double* qvel = d->qvel;
    const double* xm = d->xmat + 9 * base;
    const double* xb = d->xpos + 3 * base;
    double wl[3] = {qvel[r0 + 3], qvel[r0 + 4], qvel[r0 + 5]};
    double w[3];  /* the chassis' angular velocity, world */
    w[0] = xm[0] * wl[0] + xm[1] * wl[1] + xm[2] * wl[2];
    w[1] = xm[3] * wl[0] + xm[4] * wl[1] + xm[5] * wl[2];
    w[2] = xm[6] * wl[0] + xm[7] * wl[1] + xm[8] * wl[2];
    double mu = p[N_MU], c_alpha = p[N_C_ALPHA], c_kappa = p[N_C_KAPPA];
    double s_alpha = p[N_SIGMA_ALPHA], s_kappa = p[N_SIGMA_KAPPA];
    double crown = p[N_CROWN], loss = p[N_LOSS], k_t = p[N_K_T], c_t = p[N_C_T], v0 = p[N_V_SIGN];
    double f_total[3] = {0.0, 0.0, 0.0}, tau[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 2; k++) {
        const double* wk = p + N_WHEEL0 + W_SIZE * k;
        int slide = (int)wk[W_SLIDE], hinge = (int)wk[W_HINGE], geom = (int)wk[W_GEOM];
        double* s = st + U_WHEEL0 + S_SIZE * k;
        int qs = m->jnt_qposadr[slide], vs = m->jnt_dofadr[slide], vh = m->jnt_dofadr[hinge];
        double load = k_t * d->qpos[qs] + c_t * qvel[vs];
        if (!(load > 0.0)) {  /* lifted: no force, the patch relaxes */
            s[S_U] = 0.0; s[S_V] = 0.0; s[S_PSI] = 0.0;
            s[S_FX] = 0.0; s[S_FY] = 0.0; s[S_MZ] = 0.0; s[S_LOAD] = 0.0;
            continue;
        }
        double r = m->geom_size[3 * geom];
        const double* anchor = d->xanchor + 3 * hinge;
        const double* ah = d->xaxis + 3 * hinge;
        const double* as = d->xaxis + 3 * slide;
        /* forward e_x = axle x up (flat floor), lateral e_y = up x e_x */
        double ex0 = ah[1], ex1 = -ah[0];
        double norm = sqrt(ex0 * ex0 + ex1 * ex1);
        ex0 = ex0 / norm;
        ex1 = ex1 / norm;
        double ey0 = -ex1, ey1 = ex0;
        double pc[3] = {anchor[0], anchor[1], anchor[2] - r};  /* contact point */
        double mu_c = st[U_FIELD] > 0.0 ? friction_at(st + U_FIELD, pc[0], pc[1]) : mu;
        double rh[3] = {anchor[0] - xb[0], anchor[1] - xb[1], anchor[2] - xb[2]};
        double rc[3] = {pc[0] - xb[0], pc[1] - xb[1], pc[2] - xb[2]};
        double dc[3] = {0.0, 0.0, -r};  /* contact point from the hub */
        double wrh[3], wrc[3], spin[3];
        cross(w, rh, wrh);
        cross(w, rc, wrc);
        double qs_dot = qvel[vs], qh_dot = qvel[vh];
        double ws[3] = {qh_dot * ah[0], qh_dot * ah[1], qh_dot * ah[2]};
        cross(ws, dc, spin);
        double vh0 = qvel[r0] + wrh[0] + qs_dot * as[0];
        double vh1 = qvel[r0 + 1] + wrh[1] + qs_dot * as[1];
        double vc0 = qvel[r0] + wrc[0] + qs_dot * as[0] + spin[0];
        double vc1 = qvel[r0 + 1] + wrc[1] + qs_dot * as[1] + spin[1];
        double vx = vh0 * ex0 + vh1 * ex1;      /* rolling speed of the hub */
        double vsx = vc0 * ex0 + vc1 * ex1;     /* slip velocity of the patch, forward */
        double vsy = vc0 * ey0 + vc1 * ey1;     /* ... and sideways */
        double wz = w[2] + ws[2];               /* the wheel's yaw rate */
        double speed = fabs(vx);
        double defl = load / k_t;               /* radial deflection */
        double a = sqrt(2.0 * r * defl);        /* half contact length */
        double b = sqrt(2.0 * crown * defl);    /* half contact width */
        double kx = c_kappa * load / s_kappa, ky = c_alpha * load / s_alpha;
        double kpsi = c_kappa * load * b * b / (3.0 * s_kappa);
        double sgn = vx / sqrt(vx * vx + v0 * v0);
        double du = -vsx - speed * s[S_U] / s_kappa;
        double dv = -vsy + a / 3.0 * wz * sgn - speed * s[S_V] / s_alpha;
        double dpsi = -wz - speed * s[S_PSI] / s_kappa;
        double u = s[S_U] + dt * du, v = s[S_V] + dt * dv, psi = s[S_PSI] + dt * dpsi;
        /* brush: the linear force saturates as the patch slides, fully at 3 mu N */
        double lim = 3.0 * mu_c * load;
        double fx = kx * u, fy = ky * v;
        double lin = sqrt(fx * fx + fy * fy);
        if (lin > lim) {  /* sliding: mu N along the deflection, which goes no further */
            double slide_f = mu_c * load / lin, back = lim / lin;
            fx = fx * slide_f;
            fy = fy * slide_f;
            u = u * back;
            v = v * back;
        } else {
            double q = lin / lim;
            double scale = 1.0 - q + q * q / 3.0;
            fx = (fx + loss * kx * du) * scale;
            fy = (fy + loss * ky * dv) * scale;
        }
        double mmax = 3.0 * M_PI / 16.0 * mu_c * load * sqrt(a * b);
        double mz = kpsi * psi;
        if (fabs(mz) > mmax) {
            psi = psi * mmax / fabs(mz);
            mz = kpsi * psi;
        } else {
            mz = mz + loss * kpsi * dpsi;
        }
        s[S_U] = u; s[S_V] = v; s[S_PSI] = psi;
        s[S_FX] = fx; s[S_FY] = fy; s[S_MZ] = mz; s[S_LOAD] = load;
        double f[3] = {fx * ex0 + fy * ey0, fx * ex1 + fy * ey1, 0.0};
        /* generalized forces: the slide and the hinge of this wheel, then the chassis' free joint */
        double* qf = d->qfrc_passive;
        qf[vs] += as[0] * f[0] + as[1] * f[1];
        double arm[3];
        cross(dc, f, arm);
        qf[vh] += ah[0] * arm[0] + ah[1] * arm[1] + ah[2] * (arm[2] + mz);
        double mc[3];
        cross(rc, f, mc);
        f_total[0] += f[0];
        f_total[1] += f[1];
        tau[0] += mc[0];
        tau[1] += mc[1];
        tau[2] += mc[2] + mz;
    }
    double* qf = d->qfrc_passive + r0;
    qf[0] += f_total[0];
    qf[1] += f_total[1];
    /* torque about the chassis origin, in its own frame (R^T tau) */
    qf[3] += xm[0] * tau[0] + xm[3] * tau[1] + xm[6] * tau[2];
    qf[4] += xm[1] * tau[0] + xm[4] * tau[1] + xm[7] * tau[2];
    qf[5] += xm[2] * tau[0] + xm[5] * tau[1] + xm[8] * tau[2];
}
