/* Corrupt n samples of the nine IMU axes: scale, bias, noise, saturation, quantisation.
 *
 * The C twin of ErrorStream.corrupt_python (amr_twin/sensors/imu_errors.py): the same
 * operations in the same order on IEEE doubles (compiled with -ffp-contract=off; round half
 * to even as numpy's round), so both give the same bits; tests/sensors/test_imu_errors.py
 * checks it. Built at first use (amr_twin/base/native_build.py).
 */
#include <math.h>
#include "c_layout.h"

typedef struct {
    double scale1[9];     /* 1 + scale error of each axis */
    double range[9];      /* saturation, SI unit */
    double res[9];        /* resolution (1 where not quantised) */
    double inv_res[9];    /* 1 / res */
    int quantised[9];     /* resolution > 0 */
} imu_axes;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(imu_axes), AMR_FIELD(imu_axes, scale1), AMR_FIELD(imu_axes, range),
           AMR_FIELD(imu_axes, res), AMR_FIELD(imu_axes, inv_res), AMR_FIELD(imu_axes, quantised))

/* out (n, 9) = quantise(clip(scale1 * true + bias + noise, +-range)), row-major arrays. */
void imu_corrupt(int n, const double* true_, const double* bias, const double* noise, const imu_axes* a,
                 double* out) {
    for (int k = 0; k < n; k++) {
        for (int j = 0; j < 9; j++) {
            int i = 9 * k + j;
            double y = a->scale1[j] * true_[i] + bias[i] + noise[i];
            y = y < -a->range[j] ? -a->range[j] : y;  /* numpy's maximum then minimum (NaN passes) */
            y = y > a->range[j] ? a->range[j] : y;
            out[i] = a->quantised[j] ? nearbyint(y * a->inv_res[j]) * a->res[j] : y;
        }
    }
}
