/* A chunk of the loop's physics in one call: mj_step to each record-grid instant, the loop
 * sensors' row kept, and the grid samplers that have a C form run there, in their order.
 *
 * The C twin of the grid loop of Twin._step_physics (amr_twin/sim/loop.py): the same mj_step
 * calls in the same order and, at each instant, the same helpers the Python samplers call
 * (rr_update, battery_account, actors_update, contacts_changed, the row keepers' rr_support_row, gs_gather
 * and actors_row), so
 * both give the same bits;
 * tests/sim/test_grid_steps.py compares runs of each. A sampler may hand the instant back to
 * Python (gs_ctx.handoff: the collision monitor when the contacts changed, a row keeper when
 * its rows are full or, after keeping one, when its owner has work due, as the LiDAR's cast);
 * the loop then runs that sampler's Python side and the samplers after it.
 *
 * MuJoCo's sensors are computed on the last step before each instant only (mjDSBL_SENSOR set on
 * the others, the model's flags restored after): the rows, the samplers and whatever reads
 * sensordata after the call see the same values, and no sensor feeds the dynamics, so the
 * state is the same to the bit (docs/reference/speed.md has the cost it saves).
 *
 * mj_step is called through a pointer into the libmujoco the bindings loaded. MuJoCo's errors
 * are caught as the bindings catch them: mju_user_error points to a handler that jumps back
 * here for the length of the call (then restored); the call returns -1 with the message.
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
 */
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <mujoco/mujoco.h>
#include "c_layout.h"

enum { GS_CALL2 = 0, GS_CALL3 = 1, GS_CALL4 = 2, GS_CHANGED = 3, GS_ROW = 4, GS_TIMED = 5 };

typedef struct {
    int kind;           /* how fn is called (the enum above) */
    int width, cap, n;  /* GS_ROW: values a row (the instant first), rows of room in out, rows kept */
    int64_t period_us;  /* runs at the grid instants t >= start_us with t % period_us == 0 */
    int64_t start_us;
    int64_t due_us;     /* GS_ROW: from this instant on, a row kept hands the instant to Python */
    void* fn;
    void* a[4];         /* fn's arguments (GS_ROW: a[0..2], then the row after its instant) */
    double* out;        /* GS_ROW: (cap, width) rows */
} gs_sampler;

/* A row keeper's values: row[k] = *at[k] for k < *n (MjData values where they lie). */
void gs_gather(const double* const* at, const int* n, const void* unused, double* row) {
    (void)unused;
    for (int k = 0; k < *n; k++)
        row[k] = *at[k];
}

typedef struct {
    void (*step)(const mjModel*, mjData*);
    void (**user_error)(const char*);  /* libmujoco's mju_user_error */
    const mjModel* m;
    mjData* d;
    const double* sensors;  /* the loop sensors (ncol values of d->sensordata) */
    int ncol, rows_cap;
    double* rows;           /* (rows_cap, ncol) rows at the instants stepped to */
    int every;              /* steps between grid instants */
    int64_t grid_us;
    gs_sampler** s;
    int ns;
    int handoff;            /* -1, or the sampler that hands the last instant to Python */
    char message[256];      /* MuJoCo's error, when the call returns -1 */
} gs_ctx;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(gs_sampler), AMR_FIELD(gs_sampler, kind), AMR_FIELD(gs_sampler, width),
           AMR_FIELD(gs_sampler, cap), AMR_FIELD(gs_sampler, n), AMR_FIELD(gs_sampler, period_us),
           AMR_FIELD(gs_sampler, start_us), AMR_FIELD(gs_sampler, due_us), AMR_FIELD(gs_sampler, fn),
           AMR_FIELD(gs_sampler, a), AMR_FIELD(gs_sampler, out), AMR_STRUCT(gs_ctx), AMR_FIELD(gs_ctx, step),
           AMR_FIELD(gs_ctx, user_error), AMR_FIELD(gs_ctx, m), AMR_FIELD(gs_ctx, d),
           AMR_FIELD(gs_ctx, sensors), AMR_FIELD(gs_ctx, ncol), AMR_FIELD(gs_ctx, rows_cap),
           AMR_FIELD(gs_ctx, rows), AMR_FIELD(gs_ctx, every), AMR_FIELD(gs_ctx, grid_us),
           AMR_FIELD(gs_ctx, s), AMR_FIELD(gs_ctx, ns), AMR_FIELD(gs_ctx, handoff),
           AMR_FIELD(gs_ctx, message))

static _Thread_local jmp_buf gs_jump;
static _Thread_local gs_ctx* gs_current;

static void gs_on_error(const char* msg) {
    if (gs_current == NULL)  /* not inside gs_run on this thread: nowhere to return to */
        abort();
    strncpy(gs_current->message, msg, sizeof gs_current->message - 1);
    gs_current->message[sizeof gs_current->message - 1] = '\0';
    longjmp(gs_jump, 1);
}

/* Step nfirst steps to the first of nmarks grid instants (t_first_us), then every steps to
 * each next one; at each, keep the row and run the samplers due. Returns the instants
 * reached (rows kept): nmarks, or fewer when a sampler handed the last one to Python
 * (c->handoff >= 0, the samplers before it ran); -1 on a MuJoCo error; -2 (nothing done) when
 * the rows have no room for nmarks or a step count is below 1. */
int gs_run(gs_ctx* c, int nfirst, int nmarks, int64_t t_first_us) {
    c->handoff = -1;
    if (nmarks > c->rows_cap || nfirst < 1 || c->every < 1)
        return -2;
    void (*saved)(const char*) = *c->user_error;
    mjModel* m = (mjModel*)c->m;  /* its sensor flag toggled, then restored */
    const int flags = m->opt.disableflags;
    gs_current = c;
    *c->user_error = gs_on_error;
    if (setjmp(gs_jump)) {
        m->opt.disableflags = flags;
        *c->user_error = saved;
        gs_current = NULL;
        return -1;
    }
    int n = nfirst, j = 0;
    for (; j < nmarks; j++) {
        m->opt.disableflags = flags | mjDSBL_SENSOR;
        for (int i = 1; i < n; i++)
            c->step(c->m, c->d);
        m->opt.disableflags = flags;
        c->step(c->m, c->d);
        n = c->every;
        memcpy(c->rows + (size_t)j * c->ncol, c->sensors, sizeof(double) * c->ncol);
        int64_t t = t_first_us + j * c->grid_us;
        for (int i = 0; i < c->ns; i++) {
            gs_sampler* g = c->s[i];
            if ((g->period_us > 1 && t % g->period_us != 0) || t < g->start_us)
                continue;
            void** a = g->a;
            switch (g->kind) {
            case GS_CALL2:
                ((void (*)(void*, void*))g->fn)(a[0], a[1]);
                break;
            case GS_CALL3:
                ((void (*)(void*, void*, void*))g->fn)(a[0], a[1], a[2]);
                break;
            case GS_CALL4:
                ((void (*)(void*, void*, void*, void*))g->fn)(a[0], a[1], a[2], a[3]);
                break;
            case GS_TIMED:  /* fn(a0, a1, the instant in us) */
                ((void (*)(void*, void*, int64_t))g->fn)(a[0], a[1], t);
                break;
            case GS_CHANGED:
                if (((int (*)(void*, void*))g->fn)(a[0], a[1])) {
                    c->handoff = i;
                    *c->user_error = saved;
                    gs_current = NULL;
                    return j + 1;
                }
                break;
            case GS_ROW:
                if (g->n >= g->cap) {  /* full: Python grows the room and keeps the row */
                    c->handoff = i;
                    *c->user_error = saved;
                    gs_current = NULL;
                    return j + 1;
                }
                double* row = g->out + (size_t)g->n * g->width;
                row[0] = (double)t;
                ((void (*)(void*, void*, void*, double*))g->fn)(a[0], a[1], a[2], row + 1);
                g->n++;
                if (t >= g->due_us) {  /* kept; what follows is Python's */
                    c->handoff = i;
                    *c->user_error = saved;
                    gs_current = NULL;
                    return j + 1;
                }
                break;
            }
        }
    }
    *c->user_error = saved;
    gs_current = NULL;
    return nmarks;
}
