/* Beams of the RPLIDAR A1: directions at their own instants, motion correction, range noise.
 *
 * The C twins of interpolate_poses with world_directions, motion_correction_m and quantised_ranges
 * in amr_twin/sensors/lidar_beams.py (PythonBeamKernels in lidar_kernels.py): the same operations in the same order on IEEE doubles
 * (compiled with -ffp-contract=off; +, -, *, / and sqrt are correctly rounded, round half to
 * even as numpy's round), so both give the same bits; tests/sensors/test_lidar_kernels.py
 * checks it. lb_cast runs the three steps of a cast at the beams' own instants in one call: the
 * directions, MuJoCo's mj_multiRay (through a pointer to it, taken from the loaded libmujoco)
 * and the motion correction. Built at first use (amr_twin/sim/native_build.py).
 */
#include <math.h>
#include <stdint.h>
#include <mujoco/mujoco.h>

/* Laser pose of each of k beams at its instant t_us[i], linear between the pose samples
 * (rows: npose rows of t_us, position (3), laser x axis (3), laser y axis (3); held outside
 * them), the beam's unit direction in the world u (k, 3) from its laser-frame components
 * lx[i], ly[i], and shift (k, 3) = origin - the laser position at its instant. */
void lb_geometry(int k, const int64_t* t_us, const double* lx, const double* ly,
                 const double* rows, int npose, const double* origin, double* u, double* shift) {
    for (int i = 0; i < k; i++) {
        double p[9];
        const double* p0 = rows + 1;
        if (npose < 2) {
            for (int c = 0; c < 9; c++) p[c] = p0[c];
        } else {
            double t = (double)t_us[i];
            int j = 0;  /* searchsorted(side="right") - 1, clipped to [0, npose - 2] */
            while (j < npose && rows[10 * j] <= t) j++;
            j -= 1;
            if (j < 0) j = 0;
            if (j > npose - 2) j = npose - 2;
            const double* r0 = rows + 10 * j;
            const double* r1 = r0 + 10;
            double t0 = r0[0];
            double a = ((double)t_us[i] - t0) / (r1[0] - t0);
            a = a < 0.0 ? 0.0 : a;  /* NaN passes as numpy's maximum / minimum */
            a = a > 1.0 ? 1.0 : a;
            for (int c = 0; c < 9; c++) p[c] = r0[1 + c] + a * (r1[1 + c] - r0[1 + c]);
        }
        double* ui = u + 3 * i;
        for (int c = 0; c < 3; c++) ui[c] = p[3 + c] * lx[i] + p[6 + c] * ly[i];
        double norm = sqrt(ui[0] * ui[0] + ui[1] * ui[1] + ui[2] * ui[2]);
        for (int c = 0; c < 3; c++) ui[c] = ui[c] / norm;
        for (int c = 0; c < 3; c++) shift[3 * i + c] = origin[c] - p[c];
    }
}

/* dist[i] += n.shift / n.u for the k beams (0 where |n.u| <= 1e-3: no hit or grazing). */
void lb_correct(int k, const double* normal, const double* u, const double* shift, double* dist) {
    for (int i = 0; i < k; i++) {
        const double* n = normal + 3 * i;
        const double* ui = u + 3 * i;
        const double* s = shift + 3 * i;
        double nu = n[0] * ui[0] + n[1] * ui[1] + n[2] * ui[2];
        double ns = n[0] * s[0] + n[1] * s[1] + n[2] * s[2];
        dist[i] = dist[i] + (fabs(nu) > 1e-3 ? ns / nu : 0.0);
    }
}

/* Noisy, quantised ranges (float32, inf where invalid) of n true distances from n standard
 * normals z: sigma = max(floor, frac r), r + sigma z, rounded to res (when > 0), valid when a
 * geom was hit and range_min <= r <= range_max. */
void lb_noise(int n, const double* dist, const int32_t* geomid, const double* z, double floor_m,
              double frac, double res_m, double range_min_m, double range_max_m, float* out) {
    for (int i = 0; i < n; i++) {
        double s = frac * dist[i];
        double sigma = floor_m >= s ? floor_m : s;
        double r = dist[i] + sigma * z[i];
        if (res_m > 0.0) r = nearbyint(r / res_m) * res_m;
        int valid = geomid[i] >= 0 && r >= range_min_m && r <= range_max_m;
        out[i] = valid ? (float)r : INFINITY;
    }
}

typedef void (*lb_multiray_fn)(const mjModel* m, mjData* d, const mjtNum pnt[3], const mjtNum* vec,
                               const mjtByte* geomgroup, mjtBool flg_static, int bodyexclude,
                               int* geomid, mjtNum* dist, mjtNum* normal, int nray, mjtNum cutoff);

typedef struct {
    lb_multiray_fn multiray;  /* MuJoCo's mj_multiRay */
    const mjtByte* groups;    /* (6,) the geom groups the rays see */
    int site;                 /* the laser site */
    double cutoff;            /* culling distance, m */
    double* u;                /* (n, 3) work: directions */
    double* shift;            /* (n, 3) work: origin shifts */
    double* normal;           /* (n, 3) work: hit normals */
} lb_caster;

/* Cast k beams from the present laser origin, each along its direction at its own instant, and
 * correct the ranges for the origin's motion since: dist (k,) m (-1: no hit), geomid (k,). */
void lb_cast(const lb_caster* c, const mjModel* m, mjData* d, int k, const int64_t* t_us, const double* lx,
             const double* ly, const double* rows, int npose, double* dist, int* geomid) {
    const double* origin = d->site_xpos + 3 * c->site;
    lb_geometry(k, t_us, lx, ly, rows, npose, origin, c->u, c->shift);
    c->multiray(m, d, origin, c->u, c->groups, 1, -1, geomid, dist, c->normal, k, c->cutoff);
    lb_correct(k, c->normal, c->u, c->shift, dist);
}
