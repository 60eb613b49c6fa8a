/* The obstacle layer's clearing march: the C twin of the ray march in Costmap.update_scan
 * (amr_twin/navigation/costmap.py, where the layer and nav2's raytrace clearing are described).
 *
 * Each beam is sampled every ``step`` from its origin o to its free length, the samples' cells found
 * as Costmap.cells finds them (the same double operations in the same order: the same cells), and the
 * flat index of every sample's cell that the layer holds marked is written out, in beam order (with
 * repeats; the caller keeps the distinct ones). One pass instead of some twenty NumPy calls on arrays of
 * every sample of the scan (about 50 000). Built at first use (amr_twin/base/native_build.py).
 */
#include <math.h>
#include <stdint.h>

int64_t costmap_crossed(int n, const double* o, const double* u, const double* free_len, double step,
                        double origin_x, double origin_y, double res, int rows, int cols,
                        const uint8_t* marked, int64_t* out) {
    int64_t m = 0;
    for (int b = 0; b < n; ++b) {
        if (!(free_len[b] > 0.0)) continue;
        int64_t count = (int64_t)floor(free_len[b] / step) + 1;
        for (int64_t i = 0; i < count; ++i) {
            double d = (double)i * step;
            double x = o[2 * b] + d * u[2 * b], y = o[2 * b + 1] + d * u[2 * b + 1];
            double fc = floor((x - origin_x) / res), fr = floor((y - origin_y) / res);
            if (!(fr >= 0.0 && fr < rows && fc >= 0.0 && fc < cols)) continue;
            int64_t flat = (int64_t)fr * cols + (int64_t)fc;
            if (marked[flat]) out[m++] = flat;
        }
    }
    return m;
}
