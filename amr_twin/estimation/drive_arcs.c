/* A differential drive's pose carried along two wheel speed profiles: the C twin of
 * integrate (amr_twin/estimation/dead_reckoning.py) with the drive geometry of DriveGeometry.
 *
 * The same operations in the same order on IEEE doubles (compiled with -ffp-contract=off):
 * the pieces between the profiles' distinct knots, each piece's speeds from the knots in force
 * at its start (SpeedProfile.segment: the last knot at or before it), one arc where both
 * speeds stay constant, else ceil(span / max_substep) arcs at the mid-step speeds; sin and cos
 * called one by one through pointers, as Python's math module calls them (no fused sincos), so
 * both give the same bits; tests/estimation/test_drive_arcs.py checks it. Built at first use
 * (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <stdint.h>

#define DR_PI 3.141592653589793 /* math.pi: the double nearest pi */

static double (*volatile dr_sin)(double) = sin;
static double (*volatile dr_cos)(double) = cos;

/* The knot in force just after t: the index of the last knot at or before t (0 if none). */
static int segment_start(const int64_t* ts, int n, int64_t t) {
    int lo = 0, hi = n; /* bisect_right */
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (t < ts[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo - 1 > 0 ? lo - 1 : 0;
}

typedef struct {
    int64_t t0, t1;
    double r0, r1;
} piece;

static piece segment(const int64_t* ts, const double* rs, int n, int64_t t) {
    int i = segment_start(ts, n, t);
    piece s = {ts[i], ts[i], rs[i], rs[i]};
    if (i + 1 < n) {
        s.t1 = ts[i + 1];
        s.r1 = rs[i + 1];
    }
    return s;
}

static double speed_at(piece s, int64_t t) {
    if (s.t1 <= s.t0)
        return s.r0;
    return s.r0 + (s.r1 - s.r0) * (double)(t - s.t0) / (double)(s.t1 - s.t0);
}

/* arc of dead_reckoning.py after the body twist of the wheel speeds (DriveGeometry). */
static void drive_arc(double* pose, double left, double right, const double* geom, double dt_s) {
    double v_left = left * 2.0 * DR_PI / 60.0 * geom[0];
    double v_right = right * 2.0 * DR_PI / 60.0 * geom[1];
    double v = 0.5 * (v_left + v_right), w = (v_right - v_left) / geom[2];
    double x = pose[0], y = pose[1], yaw0 = pose[2];
    double dyaw = w * dt_s;
    if (fabs(dyaw) < 1e-9) {
        double mid = yaw0 + 0.5 * dyaw;
        pose[0] = x + v * dt_s * dr_cos(mid);
        pose[1] = y + v * dt_s * dr_sin(mid);
        pose[2] = yaw0 + dyaw;
        return;
    }
    double radius_m = v / w;
    pose[0] = x + radius_m * (dr_sin(yaw0 + dyaw) - dr_sin(yaw0));
    pose[1] = y - radius_m * (dr_cos(yaw0 + dyaw) - dr_cos(yaw0));
    pose[2] = yaw0 + dyaw;
}

/* The pose (x, y, yaw; in and out) carried from t_us to t_end_us along the left (tl, rl: nl
 * knots) and right (tr, rr: nr knots) profiles, their knots in time order, with the left and
 * right wheel radius and the wheel separation, m. Returns the arcs drawn, or -1 when
 * max_substep_us < 1 or a profile has no knot. */
int dr_integrate(const int64_t* tl, const double* rl, int nl, const int64_t* tr, const double* rr,
                 int nr, int64_t t_us, double* pose, int64_t t_end_us, int64_t max_substep_us,
                 double left_radius_m, double right_radius_m, double separation_m) {
    if (max_substep_us < 1 || nl < 1 || nr < 1)
        return -1;
    const double geom[3] = {left_radius_m, right_radius_m, separation_m};
    int il = 0, ir = 0, arcs = 0;
    int64_t t = t_us;
    for (;;) {
        /* the next distinct knot of either profile strictly between t and t_end_us */
        while (il < nl && tl[il] <= t)
            il++;
        while (ir < nr && tr[ir] <= t)
            ir++;
        int64_t t_next = t_end_us;
        if (il < nl && tl[il] < t_next)
            t_next = tl[il];
        if (ir < nr && tr[ir] < t_next)
            t_next = tr[ir];
        if (t_next <= t)
            return arcs;
        piece sl = segment(tl, rl, nl, t), sr = segment(tr, rr, nr, t);
        int64_t n = 1;
        if (!(speed_at(sl, t) == speed_at(sl, t_next) && speed_at(sr, t) == speed_at(sr, t_next)))
            n = (t_next - t + max_substep_us - 1) / max_substep_us;
        double dt_us = (double)(t_next - t) / (double)n;
        double dt_s = dt_us * 1e-6;
        double rise_l = sl.r1 - sl.r0, rise_r = sr.r1 - sr.r0;
        double span_l = (double)(sl.t1 - sl.t0), span_r = (double)(sr.t1 - sr.t0);
        for (int64_t k = 0; k < n; k++) {
            double mid = (double)t + ((double)k + 0.5) * dt_us;
            double left = sl.t1 <= sl.t0 ? sl.r0 : sl.r0 + rise_l * (mid - (double)sl.t0) / span_l;
            double right = sr.t1 <= sr.t0 ? sr.r0 : sr.r0 + rise_r * (mid - (double)sr.t0) / span_r;
            drive_arc(pose, left, right, geom, dt_s);
        }
        arcs += (int)n;
        t = t_next;
    }
}

/* twist_step of dead_reckoning.py: the pose after dt_s at the body twist (vx, vy, w). */
static void twist_step(double* pose, double vx, double vy, double w, double dt_s) {
    double x = pose[0], y = pose[1], yaw = pose[2];
    double th = w * dt_s, a, b;
    if (fabs(th) < 1e-9) {
        a = dt_s;
        b = 0.5 * th * dt_s;
    } else {
        a = dr_sin(th) / w;
        b = (1.0 - dr_cos(th)) / w;
    }
    double dx = a * vx - b * vy, dy = b * vx + a * vy;
    double c = dr_cos(yaw), s = dr_sin(yaw);
    pose[0] = x + c * dx - s * dy;
    pose[1] = y + s * dx + c * dy;
    pose[2] = yaw + th;
}

static double py_max(double a, double b) { return b > a ? b : a; } /* Python's max(a, b) */
static double py_min(double a, double b) { return b < a ? b : a; } /* Python's min(a, b) */

/* The forward integration of PublishedPose.advance (amr_twin/estimation/published_pose.py) along
 * the left (tl, rl) and right (tr, rr) profiles. ints: their knot counts, the start and end
 * instant, us, and the longest substep, us; io (13 values): the pose (x, y, yaw) and the left and
 * right RPM it moves with (both in and out), the fastest change of each speed, RPM/us, the
 * correction twist (vx, vy, w) and the geometry as dr_integrate's. Returns the steps taken, or -1
 * as dr_integrate. */
int pp_advance(const int64_t* tl, const double* rl, const int64_t* tr, const double* rr,
               const int64_t* ints, double* io) {
    const int nl = (int)ints[0], nr = (int)ints[1];
    const int64_t t_us = ints[2], now_us = ints[3], max_substep_us = ints[4];
    double *pose = io, *used = io + 3;
    const double *accel = io + 5, *corr = io + 7, *geom = io + 10;
    if (max_substep_us < 1 || nl < 1 || nr < 1)
        return -1;
    const int steady = corr[0] == 0.0 && corr[1] == 0.0 && corr[2] == 0.0;
    int il = 0, ir = 0, steps = 0;
    int64_t t = t_us;
    while (t < now_us) {
        while (il < nl && tl[il] <= t)
            il++;
        while (ir < nr && tr[ir] <= t)
            ir++;
        int64_t t_next = now_us;
        if (il < nl && tl[il] < t_next)
            t_next = tl[il];
        if (ir < nr && tr[ir] < t_next)
            t_next = tr[ir];
        piece seg[2] = {segment(tl, rl, nl, t), segment(tr, rr, nr, t)};
        while (t < t_next) {
            steps++;
            if (steady) {
                double l0 = speed_at(seg[0], t), r0 = speed_at(seg[1], t);
                if (l0 == used[0] && r0 == used[1] && speed_at(seg[0], t_next) == l0 &&
                    speed_at(seg[1], t_next) == r0) {
                    drive_arc(pose, used[0], used[1], geom, (double)(t_next - t) * 1e-6);
                    t = t_next;
                    continue;
                }
            }
            int64_t t1 = t + max_substep_us < t_next ? t + max_substep_us : t_next;
            int64_t dt = t1 - t;
            double mean[2];
            for (int w = 0; w < 2; w++) {
                double goal = speed_at(seg[w], t1);
                double step = accel[w] * (double)dt;
                double now = py_min(py_max(goal, used[w] - step), used[w] + step);
                mean[w] = 0.5 * (used[w] + now);
                used[w] = now;
            }
            double v_left = mean[0] * 2.0 * DR_PI / 60.0 * geom[0];
            double v_right = mean[1] * 2.0 * DR_PI / 60.0 * geom[1];
            double v = 0.5 * (v_left + v_right), w_rad_s = (v_right - v_left) / geom[2];
            twist_step(pose, v + corr[0], corr[1], w_rad_s + corr[2], (double)dt * 1e-6);
            t = t1;
        }
    }
    return steps;
}
