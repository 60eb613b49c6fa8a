/* The layout table a C helper exports, so that its ctypes twin is checked against it at load.
 *
 * A helper whose structs Python builds or reads lists every field of each of them:
 *
 *     AMR_LAYOUT(AMR_STRUCT(battery_state), AMR_FIELD(battery_state, soc), ...)
 *
 * which defines the exported table ``amr_layout``: the struct's size, then each field's
 * name, offset and size in bytes, ended by an empty row. amr_twin/base/c_layout.py compares
 * it with the ctypes Structure registered for the struct (names in order, offsets, sizes)
 * when the helper is loaded; a difference makes the Python twin run and says why, once.
 */
#ifndef AMR_C_LAYOUT_H
#define AMR_C_LAYOUT_H
#include <stddef.h>

typedef struct {
    const char* type;   /* the struct's typedef name */
    const char* field;  /* NULL: the row of the struct's size */
    size_t offset;      /* bytes from the struct's start */
    size_t size;        /* bytes (the struct's sizeof on its own row) */
} amr_layout_entry;

#define AMR_STRUCT(T) {#T, NULL, 0, sizeof(T)}
#define AMR_FIELD(T, f) {#T, #f, offsetof(T, f), sizeof(((T*)0)->f)}
#define AMR_LAYOUT(...) const amr_layout_entry amr_layout[] = {__VA_ARGS__, {NULL, NULL, 0, 0}};

#endif
