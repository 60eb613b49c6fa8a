/* Whether the geom pairs in contact changed since the last grid instant: the collision
 * monitor's common case in one call (amr_twin/sim/collisions.py, CollisionMonitor).
 *
 * Its Python twin is the monitor's own comparison of d.contact.geom with the pairs it kept;
 * tests/sim/test_collisions.py runs collisions with each and compares the episodes.
 * Built at first use against the installed MuJoCo's headers (amr_twin/base/native_build.py).
 */
#include <mujoco/mujoco.h>
#include "c_layout.h"

typedef struct {
    int valid;   /* the kept pairs stand for a verdict that cannot change while they do */
    int n;       /* pairs kept */
    int cap;     /* room in pairs */
    int* pairs;  /* (cap, 2) geom ids */
} contact_memo;

/* The layout of the structs above, checked against their ctypes twins at load (c_layout.h). */
AMR_LAYOUT(AMR_STRUCT(contact_memo), AMR_FIELD(contact_memo, valid), AMR_FIELD(contact_memo, n),
           AMR_FIELD(contact_memo, cap), AMR_FIELD(contact_memo, pairs))

/* 0 when the memo is valid and the pairs in contact are the kept ones (in order); otherwise
 * keeps the present pairs (if they fit; else leaves the memo invalid) and returns 1. */
int contacts_changed(const mjData* d, contact_memo* s) {
    int n = d->ncon;
    if (s->valid && n == s->n) {
        int i = 0;
        for (; i < n; i++) {
            const int* g = d->contact[i].geom;
            if (g[0] != s->pairs[2 * i] || g[1] != s->pairs[2 * i + 1]) break;
        }
        if (i == n) return 0;
    }
    s->valid = 0;
    if (n > s->cap) {
        s->n = -1;
        return 1;
    }
    for (int i = 0; i < n; i++) {
        s->pairs[2 * i] = d->contact[i].geom[0];
        s->pairs[2 * i + 1] = d->contact[i].geom[1];
    }
    s->n = n;
    return 1;
}
