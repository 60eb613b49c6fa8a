/* The MPPI controller's sampling, rollout sums and critics: the C twin of Mppi._sample (with _feasible),
 * Mppi.rollout (around NumPy's cos and sin) in amr_twin/navigation/mppi.py and MppiCritics.costs (with
 * _people_costs) in amr_twin/navigation/mppi_critics.py
 * (the critics, their symbols and their sources are described there). Arrays are time-major as there:
 * controls (T, K, 2), trajectories (T, K).
 *
 * The same operations as the NumPy twin, in the same precision: the ramps' clipping in float32 (the same
 * bits), the footprint outline's points and the people circles' centres in float32 from the NumPy rollout's
 * positions and cos/sin of the headings (the same bits, so the same costmap cells and the same collisions), the map lookups and the
 * people's and the path's distances in double (the same bits: a minimum of squares, then its square root,
 * is the minimum of the roots), and the means in the twin's precision and order; the costs agree with the
 * twin's to rounding. One pass over the samples instead of some hundred NumPy calls on (T, K) arrays.
 * Built at first use (amr_twin/base/native_build.py); without it the NumPy twin runs.
 */
#include <math.h>
#include <stdint.h>

/* parameter layout (doubles): see PARAMS in mppi.py */
enum { P_CX0, P_CX1, P_R, P_MARGIN, P_W_COLLISION, P_W_OBSTACLE, P_W_ALIGN, P_W_PROGRESS, P_W_GOAL, P_W_FORWARD,
       P_W_SOCIAL, P_W_PEOPLE_COLLISION, P_W_PEOPLE, P_PERSON_RADIUS, P_CLEARANCE, P_PERSON_MARGIN, P_SOCIAL_RADIUS,
       P_ORIGIN_X, P_ORIGIN_Y, P_RES, P_REACH_X, P_REACH_Y, P_GOAL_X, P_GOAL_Y, P_FOLLOW, P_CHECK, P_SIZE };

int mppi_params_size(void) { return P_SIZE; }

/* u (T, K, 2) clipped in place to [u_min, u_max] and, step by step from (v0, w0), to the ramps down/up. */
static void mppi_feasible(int T, int K, float* u, const float* u_min, const float* u_max, const float* down,
                   const float* up, float v0, float w0) {
    for (int k = 0; k < K; ++k) {
        float prev[2] = {v0, w0};
        for (int t = 0; t < T; ++t) {
            float* step = u + ((int64_t)t * K + k) * 2;
            for (int j = 0; j < 2; ++j) {
                float a = step[j];
                a = a < u_min[j] ? u_min[j] : a;
                a = a > u_max[j] ? u_max[j] : a;
                float lo = prev[j] - down[j], hi = prev[j] + up[j];
                a = a < lo ? lo : a;
                a = a > hi ? hi : a;
                step[j] = a;
                prev[j] = a;
            }
        }
    }
}

/* u (T, K, 2) of standard normal draws made the samples in place: scaled by sigma (2,), about the nominal
 * (T, 2) (doubles, the sum rounded to float32 as NumPy's in-place add does), sample 0 the nominal itself,
 * sample 1 braking (zeros), then clipped (mppi_feasible). */
void mppi_sample(int T, int K, float* u, const float* sigma, const double* nominal, const float* u_min,
                 const float* u_max, const float* down, const float* up, float v0, float w0) {
    for (int t = 0; t < T; ++t) {
        float* row = u + (int64_t)t * K * 2;
        for (int k = 0; k < K; ++k)
            for (int j = 0; j < 2; ++j) row[2 * k + j] = (float)((double)(row[2 * k + j] * sigma[j]) + nominal[2 * t + j]);
        for (int j = 0; j < 2; ++j) {
            row[j] = (float)nominal[2 * t + j];
            row[2 + j] = 0.0f;
        }
    }
    mppi_feasible(T, K, u, u_min, u_max, down, up, v0, w0);
}

/* The rollout's headings (T, K) from yaw0 and their midpoints over each step (Mppi.rollout's first half). */
void mppi_headings(int T, int K, const float* u, float dt, float yaw0, float* yaw, float* mid) {
    const float half = 0.5f * dt;
    for (int k = 0; k < K; ++k) {
        float acc = 0.0f;
        for (int t = 0; t < T; ++t) {
            int64_t i = (int64_t)t * K + k;
            float w = u[2 * i + 1];
            acc = t ? acc + w : w;
            yaw[i] = acc * dt + yaw0;
            mid[i] = yaw[i] - half * w;
        }
    }
}

/* The rollout's positions (T, K) from (x0, y0) with the cos cm and sin sm (T, K) of the midpoint headings. */
void mppi_positions(int T, int K, const float* u, const float* cm, const float* sm, float dt, float x0, float y0,
                    float* x, float* y) {
    for (int k = 0; k < K; ++k) {
        float ax = 0.0f, ay = 0.0f;
        for (int t = 0; t < T; ++t) {
            int64_t i = (int64_t)t * K + k;
            float v = u[2 * i], px = v * cm[i], py = v * sm[i];
            ax = t ? ax + px : px;
            ay = t ? ay + py : py;
            x[i] = ax * dt + x0;
            y[i] = ay * dt + y0;
        }
    }
}

/* Distance (float32) to the nearest lethal cell at a map point; 0 off the grid (Costmap.distance_at). */
static float lookup(const float* dist, int rows, int cols, const double* p, float x, float y) {
    double fc = floor(((double)x - p[P_ORIGIN_X]) / p[P_RES]), fr = floor(((double)y - p[P_ORIGIN_Y]) / p[P_RES]);
    if (!(fr >= 0.0 && fr < rows && fc >= 0.0 && fc < cols)) return 0.0f;
    return dist[(int64_t)fr * cols + (int64_t)fc];
}

/* The footprint critic's clearance at a pose (Mppi._footprint): the least distance over the outline (ox, oy)
 * (P,) where the centre's distance d is below check, else margin; *collide set on a lethal cell. */
static float footprint_clearance(const float* dist, int rows, int cols, const double* p, float x, float y, float c,
                                 float s, int P, const float* ox, const float* oy, float margin, int* collide) {
    float d = lookup(dist, rows, cols, p, x, y), clear = margin;
    if (d < (float)p[P_CHECK]) {
        clear = INFINITY;
        for (int j = 0; j < P; ++j) {
            float px = x + c * ox[j] - s * oy[j], py = y + s * ox[j] + c * oy[j];
            float e = lookup(dist, rows, cols, p, px, py);
            if (e < clear) clear = e;
        }
    }
    *collide = clear <= 0.0f || d <= 0.0f;
    return clear;
}

/* Cost (K,) and collision flag (K,) of the trajectories x, y (T, K) with headings' cos c and sin s (T, K),
 * controls u (T, K, 2): the costmap dist (rows, cols), the plan points ref (M, 2), the people's predicted
 * positions at (N, T, 2), the footprint's outline (ox, oy) (P,). */
void mppi_costs(int T, int K, const float* x, const float* y, const float* c, const float* s, const float* u,
                const double* p, const float* dist, int rows, int cols, const double* ref, int M,
                const double* at, int N, double* cost, uint8_t* hit, int P, const float* ox, const float* oy) {
    const float cx0 = (float)p[P_CX0], cx1 = (float)p[P_CX1];
    const float margin32 = (float)p[P_MARGIN];
    const float w_obstacle = (float)p[P_W_OBSTACLE], w_forward = (float)p[P_W_FORWARD];
    const double off = p[P_R], off_person = p[P_PERSON_RADIUS];
    /* people: the clearance the robot has now (the least over the samples' first step), as the twin */
    double now = p[P_CLEARANCE];
    if (N > 0) {
        double best = -INFINITY;
        for (int k = 0; k < K; ++k) {
            double m2 = INFINITY;
            for (int i = 0; i < 2; ++i) {
                float ox = i ? cx1 : cx0;
                float qx = x[k] + c[k] * ox, qy = y[k] + s[k] * ox;
                for (int n = 0; n < N; ++n) {
                    double dx = (double)qx - at[(int64_t)n * T * 2], dy = (double)qy - at[(int64_t)n * T * 2 + 1];
                    double d2 = dx * dx + dy * dy;
                    if (d2 < m2) m2 = d2;
                }
            }
            double g = sqrt(m2) - off - off_person;
            if (g > best) best = g;
        }
        if (best - 0.02 < now) now = best - 0.02;
    }
    for (int k = 0; k < K; ++k) {
        int first = T, first_close = T;
        float obstacle = 0.0f, forward = 0.0f;
        double align = 0.0, goal = 0.0, margin = 0.0, social = 0.0;
        for (int t = 0; t < T; ++t) {
            int64_t i = (int64_t)t * K + k;
            float ax = x[i] + c[i] * cx0, ay = y[i] + s[i] * cx0, bx = x[i] + c[i] * cx1, by = y[i] + s[i] * cx1;
            int collide;
            float clear = footprint_clearance(dist, rows, cols, p, x[i], y[i], c[i], s[i], P, ox, oy, margin32, &collide);
            if (collide && first == T) first = t;
            float rep = margin32 - clear;
            obstacle += rep > 0.0f ? rep : 0.0f;
            float back = -u[i * 2];
            forward += back > 0.0f ? back : 0.0f;
            if (p[P_FOLLOW] != 0.0) {
                if (t % 3 == 1) {
                    double m2 = INFINITY;
                    for (int m = 0; m < M; ++m) {
                        double dx = (double)x[i] - ref[2 * m], dy = (double)y[i] - ref[2 * m + 1];
                        double d2 = dx * dx + dy * dy;
                        if (d2 < m2) m2 = d2;
                    }
                    align += sqrt(m2);
                }
            } else {
                goal += hypot((double)x[i] - p[P_GOAL_X], (double)y[i] - p[P_GOAL_Y]);
            }
            if (N > 0) {
                double m2 = INFINITY;
                for (int n = 0; n < N; ++n) {
                    const double* q = at + ((int64_t)n * T + t) * 2;
                    double d2a = ((double)ax - q[0]) * ((double)ax - q[0]) + ((double)ay - q[1]) * ((double)ay - q[1]);
                    double d2b = ((double)bx - q[0]) * ((double)bx - q[0]) + ((double)by - q[1]) * ((double)by - q[1]);
                    if (d2a < m2) m2 = d2a;
                    if (d2b < m2) m2 = d2b;
                }
                double g = sqrt(m2) - off - off_person;
                if (g < now && first_close == T) first_close = t;
                double rep_p = p[P_PERSON_MARGIN] - g;
                margin += rep_p > 0.0 ? rep_p : 0.0;
                double near = 1.0 - g / p[P_SOCIAL_RADIUS];
                float v = u[i * 2];
                social += (double)(v * v) * (near > 0.0 ? near : 0.0);
            }
        }
        double total = first < T ? p[P_W_COLLISION] * (1.0 + (double)(T - first) / T) : 0.0;
        total += (double)(w_obstacle * (obstacle / (float)T));
        if (p[P_FOLLOW] != 0.0) {
            total += p[P_W_ALIGN] * (align / ((T + 1) / 3));
            int64_t last = (int64_t)(T - 1) * K + k;
            total += p[P_W_PROGRESS] * hypot((double)x[last] - p[P_REACH_X], (double)y[last] - p[P_REACH_Y]);
        } else {
            total += p[P_W_GOAL] * (goal / T);
        }
        total += (double)(w_forward * (forward / (float)T));
        if (N > 0) {
            double people = first_close < T ? p[P_W_PEOPLE_COLLISION] * (1.0 + (double)(T - first_close) / T) : 0.0;
            people += p[P_W_PEOPLE] * (margin / T);
            total += people + p[P_W_SOCIAL] * (social / T);
        }
        cost[k] = total;
        hit[k] = first < T;
    }
}
