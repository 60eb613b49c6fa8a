/* Beams of the RPLIDAR A1: directions at their own instants, motion correction, range noise.
 *
 * The C twins of interpolate_poses with world_directions, motion_correction_m and quantised_ranges
 * in amr_twin/sensors/lidar_beams.py (PythonBeamKernels in lidar_kernels.py): the same operations in the same order on IEEE doubles
 * (compiled with -ffp-contract=off; +, -, *, / and sqrt are correctly rounded, round half to
 * even as numpy's round), so both give the same bits; tests/sensors/test_lidar_kernels.py
 * checks it. lb_cast runs the three steps of a cast at the beams' own instants in one call: the
 * directions, the rays (lb_rays: MuJoCo's mju_rayGeom per geom behind a cull of its own, azimuth
 * spans and nearest first, the hits of mj_multiRay to the bit; mj_multiRay itself when a mesh, height field or SDF is in
 * view; both through pointers taken from the loaded libmujoco) and the motion correction. Built
 * at first use (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <mujoco/mujoco.h>
#include "c_layout.h"

/* Laser pose of each of k beams at its instant t_us[i], linear between the pose samples
 * (rows: npose rows of t_us, position (3), laser x axis (3), laser y axis (3); held outside
 * them): the beam's unit direction in the world u (k, 3) from its laser-frame components
 * lx[i], ly[i], and its origin org (k, 3), m, the laser position at its instant. */
void lb_geometry(int k, const int64_t* t_us, const double* lx, const double* ly,
                 const double* rows, int npose, double* u, double* org) {
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
        for (int c = 0; c < 3; c++) org[3 * i + c] = p[c];
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
typedef mjtNum (*lb_ray_fn)(const mjModel* m, const mjData* d, const mjtNum pnt[3], const mjtNum vec[3],
                            const mjtByte* geomgroup, mjtBool flg_static, int bodyexclude, int geomid[1],
                            mjtNum normal[3]);
typedef mjtNum (*lb_raygeom_fn)(const mjtNum pos[3], const mjtNum mat[9], const mjtNum size[3],
                                const mjtNum pnt[3], const mjtNum vec[3], int geomtype, mjtNum normal[3]);

typedef struct {
    double azimuth;           /* of the geom's centre seen from the origin, rad */
    double lo, hi;            /* lowest and highest azimuth offset of its bounding box's corners, rad (+-LB_ALL: any) */
    double near_m;            /* least distance of its bounding sphere to the origin, m (0 for a plane) */
    double reach_m;           /* least horizontal distance of its bounding box's corners to the origin, m */
    int geom;                 /* its id */
} lb_geom;

typedef struct {
    lb_multiray_fn multiray;  /* MuJoCo's mj_multiRay */
    const mjtByte* groups;    /* (6,) the geom groups the rays see */
    int site;                 /* the laser site */
    double cutoff;            /* culling distance, m */
    double* u;                /* (n, 3) work: directions */
    double* org;              /* (n, 3) work: the beams' origins */
    double* normal;           /* (n, 3) work: hit normals */
    lb_raygeom_fn raygeom;    /* MuJoCo's mju_rayGeom; NULL: every cast goes to mj_multiRay */
    lb_geom* seen;            /* (ngeom,) work: the geoms a ray may hit, nearest first */
    lb_ray_fn ray;            /* MuJoCo's mj_ray (one ray from its own origin, when mj_multiRay must cast) */
} lb_caster;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(lb_caster), AMR_FIELD(lb_caster, multiray), AMR_FIELD(lb_caster, groups),
           AMR_FIELD(lb_caster, site), AMR_FIELD(lb_caster, cutoff), AMR_FIELD(lb_caster, u),
           AMR_FIELD(lb_caster, org), AMR_FIELD(lb_caster, normal), AMR_FIELD(lb_caster, raygeom),
           AMR_FIELD(lb_caster, seen), AMR_FIELD(lb_caster, ray))

#define LB_PI 3.14159265358979323846
#define LB_ALL 10.0           /* an offset span wider than any: the geom is tried by every ray */
#define LB_MARGIN_RAD 1e-9    /* widening of a span for the rounding of atan2 */

/* Bytes of an lb_geom (the caller allocates ngeom of them). */
int lb_geom_bytes(void) { return (int)sizeof(lb_geom); }

static double lb_wrap(double a) {
    return a > LB_PI ? a - 2 * LB_PI : (a <= -LB_PI ? a + 2 * LB_PI : a);
}

/* The geoms mj_multiRay(flg_static = 1, bodyexclude = -1) would try, with the azimuth span of
 * their bounding box seen from p: the centre's azimuth and the offsets of the box's corners from
 * it. The corners bound the azimuths of the box's horizontal outline (a convex polygon whose
 * angular extent, seen from outside, is reached at its vertices), so a ray whose azimuth lies
 * outside the span misses the geom; a span of pi or more (p above the outline) and a plane are
 * tried by every ray. Sorted by their least distance to p (the centre's distance less the
 * bounding sphere's radius; 0 for a plane), nearest first, so that a ray stops at the first geom
 * farther than its nearest hit. reach_m, the corners' least horizontal distance to p, lets a ray
 * from another origin use the span (lb_rays). Returns the number of geoms, or -1 when one of them
 * is a mesh, height field or SDF (MuJoCo's own ray functions: the caller casts with mj_multiRay).
 * A geom is left out when farther than the cutoff from every point within slack_m of p. */
static int lb_nearer(const void* a, const void* b) {
    const lb_geom* x = a;
    const lb_geom* y = b;
    if (x->near_m != y->near_m) return x->near_m < y->near_m ? -1 : 1;
    return x->geom - y->geom;
}

static int lb_prepare(const lb_caster* c, const mjModel* m, const mjData* d, const double* p, double slack_m) {
    int n = 0;
    for (int g = 0; g < m->ngeom; g++) {
        int mat = m->geom_matid[g];
        if (mat < 0 ? m->geom_rgba[4 * g + 3] == 0 : m->mat_rgba[4 * mat + 3] == 0) continue;  /* invisible */
        int group = m->geom_group[g] < 0 ? 0 : (m->geom_group[g] > mjNGROUP - 1 ? mjNGROUP - 1 : m->geom_group[g]);
        if (!c->groups[group]) continue;
        int type = m->geom_type[g];
        if (type == mjGEOM_MESH || type == mjGEOM_HFIELD || type == mjGEOM_SDF) return -1;
        const double* pos = d->geom_xpos + 3 * g;
        double rel[3] = {pos[0] - p[0], pos[1] - p[1], pos[2] - p[2]};
        double centre_m = sqrt(rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]);
        if (centre_m > c->cutoff + m->geom_rbound[g] + slack_m) continue;
        lb_geom* s = c->seen + n++;
        s->geom = g;
        s->azimuth = atan2(rel[1], rel[0]);
        s->lo = -LB_ALL;
        s->hi = LB_ALL;
        s->reach_m = 0.0;
        s->near_m = type == mjGEOM_PLANE || centre_m < m->geom_rbound[g] ? 0.0 : centre_m - m->geom_rbound[g];
        if (type == mjGEOM_PLANE) continue;
        const double* box = m->geom_aabb + 6 * g;  /* centre and half sizes in the geom frame */
        const double* mat9 = d->geom_xmat + 9 * g;
        double lo = 0.0, hi = 0.0, reach2 = INFINITY;
        for (int v = 0; v < 8; v++) {
            double x = box[0] + (v & 1 ? box[3] : -box[3]);
            double y = box[1] + (v & 2 ? box[4] : -box[4]);
            double z = box[2] + (v & 4 ? box[5] : -box[5]);
            double wx = mat9[0] * x + mat9[1] * y + mat9[2] * z + rel[0];
            double wy = mat9[3] * x + mat9[4] * y + mat9[5] * z + rel[1];
            double a = lb_wrap(atan2(wy, wx) - s->azimuth);
            lo = a < lo ? a : lo;
            hi = a > hi ? a : hi;
            double r2 = wx * wx + wy * wy;
            reach2 = r2 < reach2 ? r2 : reach2;
        }
        if (hi - lo < LB_PI - 1e-6) {
            s->lo = lo - LB_MARGIN_RAD;
            s->hi = hi + LB_MARGIN_RAD;
            s->reach_m = sqrt(reach2);
        }
    }
    qsort(c->seen, n, sizeof(lb_geom), lb_nearer);
    return n;
}

/* Cast k unit directions u, ray i from org + 3 * i * stride (stride 0: every ray from org), behind
 * a cull prepared once from p: for each, the nearest hit among the prepared geoms by MuJoCo's
 * mju_rayGeom (ties: the lower id, as mj_multiRay, which tries them in id order); dist (k,) m, -1
 * and geomid -1 and a zero normal where none. A ray from an origin D m from p sees each corner of a
 * geom's box at most asin(D / reach_m) off its azimuth from p (D < reach_m), so the geom's span
 * is widened by x (1 + x^2 / 4) >= asin(x), x = D / reach_m <= 1/2 (beyond: the geom is tried);
 * a widened span of pi or more (the origin may be above the outline) is tried too; and the
 * geom's bounding sphere is at least near_m - D from the origin. Returns 0, or -1 when mj_multiRay
 * must cast instead. */
static int lb_rays(const lb_caster* c, const mjModel* m, const mjData* d, const double* p, int k,
                   const double* org, int stride, const double* u, int* geomid, double* dist, double* normal) {
    double slack_m = 0.0;
    for (int i = 0; i < k && stride; i++) {
        const double* o = org + 3 * i;
        double e[3] = {o[0] - p[0], o[1] - p[1], o[2] - p[2]};
        double off_m = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        slack_m = off_m > slack_m ? off_m : slack_m;
    }
    int n = lb_prepare(c, m, d, p, slack_m);
    if (n < 0) return -1;
    for (int i = 0; i < k; i++) {
        const double* v = u + 3 * i;
        const double* o = org + 3 * i * stride;
        double e[3] = {o[0] - p[0], o[1] - p[1], o[2] - p[2]};
        double off_m = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        off_m = off_m > 0.0 ? off_m + 1e-9 : 0.0;  /* a nm for the rounding */
        double az = atan2(v[1], v[0]), best = -1.0, nrm[3] = {0.0, 0.0, 0.0}, out[3];
        int hit = -1;
        for (int j = 0; j < n; j++) {
            const lb_geom* s = c->seen + j;
            if (best >= 0 && s->near_m - off_m > best) break;  /* this geom and all after it are farther than the hit */
            if (s->lo > -LB_ALL) {
                double widen = 0.0;
                if (off_m > 0.0) {
                    double x = off_m / s->reach_m;
                    widen = x * (1.0 + 0.25 * x * x) + LB_MARGIN_RAD;
                    if (x > 0.5 || s->hi - s->lo + 2 * widen >= LB_PI - 1e-6) widen = LB_ALL;
                }
                double off = lb_wrap(az - s->azimuth);
                if (off < s->lo - widen || off > s->hi + widen) continue;
            }
            int g = s->geom;
            double x = c->raygeom(d->geom_xpos + 3 * g, d->geom_xmat + 9 * g, m->geom_size + 3 * g, o, v,
                                  m->geom_type[g], out);
            if (x >= 0 && (best < 0 || x < best || (x == best && g < hit))) {
                best = x;
                hit = g;
                nrm[0] = out[0], nrm[1] = out[1], nrm[2] = out[2];
            }
        }
        dist[i] = best;
        geomid[i] = hit;
        for (int a = 0; a < 3; a++) normal[3 * i + a] = nrm[a];
    }
    return 0;
}

/* Cast k unit directions u (k, 3), ray i from org + 3 * i * stride (stride 0: all from org, 1: each
 * from its own origin), the cull prepared from p: dist (k,) m (-1: no hit), geomid (k,), normals in
 * c->normal. Through lb_rays (MuJoCo's per-geom ray functions behind a cheaper cull than
 * mj_multiRay's, the same hits) unless a seen geom needs MuJoCo's own casts: mj_multiRay from one
 * origin, mj_ray per ray from their own (the same bits; mj_multiRay of one ray costs ~100 us among
 * the aisles world's 415 geoms, mj_ray ~5 us). */
static void lb_trace(const lb_caster* c, const mjModel* m, mjData* d, const double* p, int k, const double* org,
                     int stride, const double* u, double* dist, int* geomid) {
    if (c->raygeom && lb_rays(c, m, d, p, k, org, stride, u, geomid, dist, c->normal) == 0) return;
    if (!stride) {
        c->multiray(m, d, org, u, c->groups, 1, -1, geomid, dist, c->normal, k, c->cutoff);
        return;
    }
    for (int i = 0; i < k; i++)
        dist[i] = c->ray(m, d, org + 3 * i, u + 3 * i, c->groups, 1, -1, geomid + i, c->normal + 3 * i);
}

/* Cast k unit directions u (k, 3) from p: dist (k,) m (-1: no hit), geomid (k,), normals in c->normal. */
void lb_cast_rays(const lb_caster* c, const mjModel* m, mjData* d, const double* p, int k, const double* u,
                  double* dist, int* geomid) {
    lb_trace(c, m, d, p, k, p, 0, u, dist, geomid);
}

/* Cast k beams, each along its direction from the laser's position at its own instant (the world as
 * it is now; the cull prepared from the present laser origin): dist (k,) m (-1: no hit), geomid (k,). */
void lb_cast(const lb_caster* c, const mjModel* m, mjData* d, int k, const int64_t* t_us, const double* lx,
             const double* ly, const double* rows, int npose, double* dist, int* geomid) {
    lb_geometry(k, t_us, lx, ly, rows, npose, c->u, c->org);
    lb_trace(c, m, d, d->site_xpos + 3 * c->site, k, c->org, 1, c->u, dist, geomid);
}
