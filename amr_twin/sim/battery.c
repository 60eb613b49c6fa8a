/* The battery's 10 ms accounting: what both drivers and the auxiliary load draw, one grid instant.
 *
 * The C twin of Battery.account (amr_twin/sim/battery.py): the same operations in the same
 * order on IEEE doubles (compiled with -ffp-contract=off), so that both give the same bits;
 * tests/sim/test_battery.py checks a run of each. The state lives in the struct, which the
 * Python class reads and writes (its soc, current_a and sag_v are properties on it).
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
 */
#include <mujoco/mujoco.h>
#include "c_layout.h"

typedef struct {
    double soc, current_a, sag_v, t_last_s;       /* state: charge 0-1, pack current A, fault drop V, s */
    double terminal_v;                            /* after the last accounting: OCV - R I - sag, V */
    double empty_v, nominal_v, low_span_v, high_span_v, r_ohm, capacity_as;  /* the pack */
    double volt[2];                               /* phase voltage of each motor, V */
    int mode[2];                                  /* 0 drive, 1 coast, 2 brake (plant.MODE_CODES) */
    double ke[2], r_ohm_motor[2], limit_a[2];     /* V s/rad, ohm, A */
    double brake_limit_a, quiescent2_a, aux_w;    /* A, A (both drivers), W */
    int dof[2];                                   /* the wheel hinges' dof addresses */
    double charger_a;                             /* a charger's current limit, A (0: none) */
} battery_state;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(battery_state), AMR_FIELD(battery_state, soc), AMR_FIELD(battery_state, current_a),
           AMR_FIELD(battery_state, sag_v), AMR_FIELD(battery_state, t_last_s),
           AMR_FIELD(battery_state, terminal_v), AMR_FIELD(battery_state, empty_v),
           AMR_FIELD(battery_state, nominal_v), AMR_FIELD(battery_state, low_span_v),
           AMR_FIELD(battery_state, high_span_v), AMR_FIELD(battery_state, r_ohm),
           AMR_FIELD(battery_state, capacity_as), AMR_FIELD(battery_state, volt),
           AMR_FIELD(battery_state, mode), AMR_FIELD(battery_state, ke),
           AMR_FIELD(battery_state, r_ohm_motor), AMR_FIELD(battery_state, limit_a),
           AMR_FIELD(battery_state, brake_limit_a), AMR_FIELD(battery_state, quiescent2_a),
           AMR_FIELD(battery_state, aux_w), AMR_FIELD(battery_state, dof),
           AMR_FIELD(battery_state, charger_a))

/* Drain the pack by the present current since the last call (d->time), less what a connected
 * charger gives (up to charger_a, never above the full pack's voltage at the terminals); keep the
 * terminal voltage that current leaves (the recorder's battery_v at this grid instant). */
void battery_account(const mjData* d, battery_state* b) {
    double t = d->time;
    double dt = t - b->t_last_s;
    b->t_last_s = t;
    double s = b->soc;
    s = s > 0.0 ? s : 0.0;
    s = s < 1.0 ? s : 1.0;
    double ocv = s < 0.5 ? b->empty_v + b->low_span_v * s / 0.5
                         : b->nominal_v + b->high_span_v * (s - 0.5) / 0.5;
    double v_batt = ocv - b->r_ohm * b->current_a - b->sag_v;
    v_batt = v_batt > 1.0 ? v_batt : 1.0;
    double supply = 0.0;
    for (int w = 0; w < 2; w++) {
        double i;
        if (b->mode[w] == 1) {
            i = 0.0;
        } else {
            double limit = b->mode[w] == 2 ? b->brake_limit_a : b->limit_a[w];
            i = (b->volt[w] - b->ke[w] * d->qvel[b->dof[w]]) / b->r_ohm_motor[w];
            i = i < limit ? i : limit;
            i = i > -limit ? i : -limit;
        }
        supply = w == 0 ? b->volt[w] * i : supply + b->volt[w] * i;
    }
    double current = supply / v_batt + b->quiescent2_a + b->aux_w / v_batt;
    if (b->charger_a > 0.0) {  /* constant current, then the pack held at full: constant voltage */
        double head = b->nominal_v + b->high_span_v - ocv, charge = b->charger_a;
        if (b->r_ohm * (charge - current) > head) charge = head / b->r_ohm + current;
        current = current - (charge > 0.0 ? charge : 0.0);
    }
    b->current_a = current;
    b->soc = b->soc - current * dt / b->capacity_as;
    s = b->soc;
    s = s > 0.0 ? s : 0.0;
    s = s < 1.0 ? s : 1.0;
    ocv = s < 0.5 ? b->empty_v + b->low_span_v * s / 0.5 : b->nominal_v + b->high_span_v * (s - 0.5) / 0.5;
    b->terminal_v = ocv - b->r_ohm * current - b->sag_v;
}
