/* The bridge's grid-sampled state messages of a tick in one call: the C twin of
 * StateBlocks.blocks' Python form (amr_twin/ros1/frame_blocks.py), which is
 * StateSampler.arrays (amr_twin/ros/ros_state.py) then StateBlocks' three record blocks.
 *
 * A sample row is t_us, the joints' q (nj), qd (nj), the base's twist in the world (6), the
 * positions (3 nb) and orientations w, x, y, z (4 nb) of base_link and the nb - 1 moving links.
 * Each record is a copy of its template (the constant bytes: lengths, frame names, zero
 * covariances) with the stamps and values written at the offsets Python gives. The same
 * operations in the same order on IEEE doubles as numpy's (compiled with -ffp-contract=off), so
 * both give the same bytes; tests/ros1/test_frame_blocks.py checks it. Built at first use
 * (amr_twin/base/native_build.py).
 */
#include <stdint.h>
#include <string.h>

static const int C1[3] = {1, 2, 0}, C2[3] = {2, 0, 1};
/* _qmul's terms: component c is the sum over k of SIGN[k][c] * a[k] * b[IB[k][c]] */
static const int IB[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
static const double SIGN[4][4] = {{1, 1, 1, 1}, {-1, 1, -1, 1}, {-1, 1, 1, -1}, {-1, -1, 1, 1}};

static void put_u32(uint8_t* at, int64_t v) {
    uint32_t u = (uint32_t)v;
    memcpy(at, &u, 4);
}

/* ROS time of t (us) at `at`: seconds, nanoseconds (floor division, as numpy's). */
static void put_stamp(uint8_t* at, int64_t t) {
    int64_t sec = t / 1000000, rem = t % 1000000;
    if (rem < 0) {
        rem += 1000000;
        sec -= 1;
    }
    put_u32(at, sec);
    put_u32(at + 4, rem * 1000);
}

/* A pose at `at`: x, y, z, then the quaternion q (w, x, y, z) as x, y, z, w. */
static void put_pose(uint8_t* at, const double* xyz, const double* q) {
    double pose[7] = {xyz[0], xyz[1], xyz[2], q[1], q[2], q[3], q[0]};
    memcpy(at, pose, sizeof pose);
}

/* R(q)^T v for a unit quaternion q (w, x, y, z): ros_state._rotate_inv. */
static void rotate_inv(const double* q, const double* v, double* out) {
    double w = q[0], u[3] = {-q[1], -q[2], -q[3]}, t[3], c[3];
    for (int i = 0; i < 3; i++)
        t[i] = 2.0 * (u[C1[i]] * v[C2[i]] - u[C2[i]] * v[C1[i]]);
    for (int i = 0; i < 3; i++)
        c[i] = u[C1[i]] * t[C2[i]] - u[C2[i]] * t[C1[i]];
    for (int i = 0; i < 3; i++)
        out[i] = v[i] + w * t[i] + c[i];
}

/* The quaternion product a b (w, x, y, z): ros_state._qmul, left to right. */
static void qmul(const double* a, const double* b, double* out) {
    for (int c = 0; c < 4; c++) {
        double s = a[0] * b[IB[0][c]];
        for (int k = 1; k < 4; k++)
            s += SIGN[k][c] * (a[k] * b[IB[k][c]]);
        out[c] = s;
    }
}

/* The n sample rows of `table` (width doubles each) into ground truths (all rows; gt NULL: none),
 * and joint states and link transforms (the rows at multiples of period_us; NULL: none).
 * gt_off: the stamp, pose and twist; js_off: the stamp, q and qd; tf_off: each link's stamp (its
 * seq first) and pose. Writes the kept rows' instants to kept_us; returns how many. */
int fb_blocks(const double* table, int n, int width, int nj, int nb, int64_t period_us,
              uint8_t* gt, const uint8_t* gt_tmpl, int gt_size, const int32_t* gt_off,
              uint8_t* js, const uint8_t* js_tmpl, int js_size, const int32_t* js_off,
              uint8_t* tf, const uint8_t* tf_tmpl, int tf_size, const int32_t* tf_off,
              int64_t* kept_us) {
    int m = 0;
    for (int r = 0; r < n; r++) {
        const double* row = table + (int64_t)r * width;
        const double *q = row + 1, *vel = row + 1 + 2 * nj, *pos = vel + 6, *quat = pos + 3 * nb;
        int64_t t = (int64_t)row[0];
        if (gt != NULL) {
            uint8_t* rec = gt + (int64_t)r * gt_size;
            double twist[6];
            memcpy(rec, gt_tmpl, gt_size);
            put_stamp(rec + gt_off[0], t);
            put_pose(rec + gt_off[1], pos, quat);
            rotate_inv(quat, vel, twist);
            memcpy(twist + 3, vel + 3, 3 * sizeof(double));
            memcpy(rec + gt_off[2], twist, sizeof twist);
        }
        if (t % period_us != 0)
            continue;
        kept_us[m] = t;
        if (js != NULL) {
            uint8_t* rec = js + (int64_t)m * js_size;
            memcpy(rec, js_tmpl, js_size);
            put_stamp(rec + js_off[0], t);
            memcpy(rec + js_off[1], q, nj * sizeof(double));
            memcpy(rec + js_off[2], q + nj, nj * sizeof(double));
        }
        if (tf != NULL) {
            uint8_t* rec = tf + (int64_t)m * tf_size;
            double inv[4] = {quat[0], -quat[1], -quat[2], -quat[3]};
            memcpy(rec, tf_tmpl, tf_size);
            for (int k = 1; k < nb; k++) {
                double d[3], lp[3], lq[4];
                for (int i = 0; i < 3; i++)
                    d[i] = pos[3 * k + i] - pos[i];
                rotate_inv(quat, d, lp);
                qmul(inv, quat + 4 * k, lq);
                put_stamp(rec + tf_off[2 * (k - 1)] + 4, t);
                put_pose(rec + tf_off[2 * (k - 1) + 1], lp, lq);
            }
        }
        m++;
    }
    return m;
}

/* The row feed's n rows of a tick (amr_twin/ros1/row_feed.py, RowFeed.blocks; its Python twin is
 * RowFeed.take and the record blocks of frame_blocks.py) into three std_msgs/Float64MultiArray
 * blocks (wheel speeds in RPM, PWM counts, motor currents) and the sensor_msgs/BatteryState
 * records of the rows whose grid index is a multiple of battery_every. rows: n x width, the wheel
 * speeds (rad/s) at columns 2, 3; pins: m x pins_width drive rows (PWM L, R, DIR L, R, mode L, R,
 * voltage L, R) in force after pin_t; bat: nb x 4 (t, V, A, soc). motors: ke, R, current limit
 * of the left, then the right motor, then the brake's limit (plant.motor_currents_a's formula,
 * numpy's maximum and minimum). vas: each row's battery V, A, soc. Returns the battery records
 * written (-1 without a battery row). */
int fb_rows(const int64_t* t, int n, const double* rows, int width, const int64_t* pin_t,
            const double* pins, int m, int pins_width, const double* bat, int nb,
            int64_t grid_us, int64_t battery_every, const double* motors, int64_t brake,
            int64_t coast, double capacity_ah, double rpm_per_rad_s, uint8_t* rpm, uint8_t* pwm,
            uint8_t* cur, const uint8_t* row_tmpl, int row_size, int row_off, uint8_t* battery,
            const uint8_t* bat_tmpl, int bat_size, const int32_t* bat_off, int64_t* bat_t,
            double* vas) {
    int k = -1, j = -1, nbat = 0;
    if (nb == 0 || m == 0)
        return -1;
    for (int r = 0; r < n; r++) {
        const double* row = rows + (int64_t)r * width;
        while (k + 1 < m && pin_t[k + 1] < t[r]) /* the last drive row before the instant */
            k++;
        while (j + 1 < nb && bat[4 * (j + 1)] <= t[r]) /* the last battery row at or before */
            j++;
        const double* pin = pins + (int64_t)(k < 0 ? 0 : k) * pins_width;
        const double* b = bat + 4 * (j < 0 ? 0 : j);
        double speed[2] = {row[2] * rpm_per_rad_s, row[3] * rpm_per_rad_s};
        double counts[2] = {(double)(int64_t)pin[0], (double)(int64_t)pin[1]};
        double amps[2];
        for (int w = 0; w < 2; w++) {
            const double* mo = motors + 3 * w;
            int64_t mode = (int64_t)pin[4 + w];
            double i = (pin[6 + w] - mo[0] * row[2 + w]) / mo[1];
            double limit = mode == brake ? motors[6] : mo[2];
            double lo = -limit;
            double x = (i >= lo || i != i) ? i : lo;
            double y = (x <= limit || x != x) ? x : limit;
            amps[w] = mode == coast ? 0.0 : y;
        }
        uint8_t* out[3] = {rpm, pwm, cur};
        const double* val[3] = {speed, counts, amps};
        for (int c = 0; c < 3; c++) {
            uint8_t* rec = out[c] + (int64_t)r * row_size;
            memcpy(rec, row_tmpl, row_size);
            memcpy(rec + row_off, val[c], 2 * sizeof(double));
        }
        vas[3 * r] = b[1];
        vas[3 * r + 1] = b[2];
        vas[3 * r + 2] = b[3];
        if ((t[r] / grid_us) % battery_every == 0) {
            uint8_t* rec = battery + (int64_t)nbat * bat_size;
            float values[7] = {(float)b[1],        0.0f, (float)(-b[2]), (float)(b[3] * capacity_ah),
                               (float)capacity_ah, (float)capacity_ah, (float)b[3]};
            memcpy(rec, bat_tmpl, bat_size);
            put_stamp(rec + bat_off[0], t[r]);
            memcpy(rec + bat_off[1], values, sizeof values);
            bat_t[nbat++] = t[r];
        }
    }
    return nbat;
}
