/* SC edges of the hall sensors inside one chunk of sampled wheel angles and speeds.
 *
 * The C twin of the core loop of HallSensors.edges_from_samples (amr_twin/sensors/hall.py):
 * the same operations in the same order on IEEE doubles (compiled with -ffp-contract=off;
 * Newton on the Hermite cubic as hall_edges.solve_hermite, round half to even as Python's
 * round), edges in the same order before the caller's stable sort by time, so both give the
 * same edges; tests/sensors/test_hall.py checks it. Built at first use
 * (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <stdint.h>

#define STEP_TOL 1e-13

static double solve_hermite(double q0, double q1, double m0, double m1, double theta) {
    double dq = q1 - q0;
    double s = q1 != q0 ? (theta - q0) / dq : 0.5;
    s = s > 0.0 ? s : 0.0;
    s = s < 1.0 ? s : 1.0;
    double a = m0 + m1 - 2.0 * dq;
    double b = 3.0 * dq - 2.0 * m0 - m1;
    double d = q0 - theta;
    double a3 = 3.0 * a, b2 = 2.0 * b;
    for (int it = 0; it < 4; it++) {
        double df = (a3 * s + b2) * s + m0;
        if (fabs(df) < 1e-12) break;
        double step = (((a * s + b) * s + m0) * s + d) / df;
        s -= step;
        s = s > 0.0 ? s : 0.0;
        s = s < 1.0 ? s : 1.0;
        if (fabs(step) < STEP_TOL) break;
    }
    return s;
}

/* 1 if some wheel's speed changes sign between two of the n + 1 samples (rows as below): the
 * caller resamples such a chunk first (a wheel may cross a boundary twice in an interval). */
int hall_reverses(int n, const double* rows, int ncol, int nw) {
    for (int w = 0; w < nw; w++)
        for (int i = 0; i < n; i++)
            if (rows[i * ncol + nw + w] * rows[(i + 1) * ncol + nw + w] < 0.0)
                return 1;
    return 0;
}

/* n + 1 samples: ts (n + 1,) us; rows (n + 1, ncol): the nw wheel angles (rad), then their
 * speeds (rad/s). offsets (nw, 3) rad, stuck (nw, 3), pitch rad, hb half the latches' hysteresis
 * band rad (a sensor toggles hb past its boundary forward, hb before it backward). count (nw, 3):
 * each sensor's toggle count at ts[0], the free sensors' final ones written back. Writes the
 * edges (time us, wheel) to out_t, out_w in the order wheel, sensor, interval, crossing. Returns
 * the number of edges, or -1 if more than cap. */
int hall_edges(int n, const int64_t* ts, const double* rows, int ncol, int nw, const double* offsets,
               const int* stuck, double pitch, double hb, int64_t* count_io, int64_t* out_t, int* out_w,
               int cap) {
    int ne = 0;
    int64_t t_first = ts[0] + 1, t_last = ts[n];
    for (int w = 0; w < nw; w++) {
        for (int k = 0; k < 3; k++) {
            if (stuck[3 * w + k]) continue;
            double off = offsets[3 * w + k];
            int64_t count = count_io[3 * w + k];
            for (int i = 0; i < n; i++) {
                double q1 = rows[(i + 1) * ncol + w];
                int64_t c1 = (int64_t)floor((q1 - off - hb) / pitch);
                int up = c1 > count;
                if (!up) {
                    c1 = (int64_t)floor((q1 - off + hb) / pitch);
                    if (c1 >= count) continue;
                }
                double q0 = rows[i * ncol + w];
                int64_t t0 = ts[i], span = ts[i + 1] - ts[i];
                double h = (double)span * 1e-6;
                double m0 = rows[i * ncol + nw + w] * h, m1 = rows[(i + 1) * ncol + nw + w] * h;
                double shift = up ? hb : -hb;
                int64_t lattice = up ? count + 1 : count, last = up ? c1 : c1 + 1;
                for (;;) {
                    if (ne >= cap) return -1;
                    double s = solve_hermite(q0, q1, m0, m1, off + pitch * (double)lattice + shift);
                    double t = (double)t0 + s * (double)span;
                    int64_t r = (int64_t)nearbyint(t);
                    r = r > t_first ? r : t_first;
                    out_t[ne] = r < t_last ? r : t_last;
                    out_w[ne] = w;
                    ne++;
                    if (lattice == last) break;
                    lattice += up ? 1 : -1;
                }
                count = c1;
            }
            count_io[3 * w + k] = count;
        }
    }
    return ne;
}
