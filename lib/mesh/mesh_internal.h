/* mesh_internal.h: what lib/mesh's own files share and nobody else uses. */
#ifndef FM_MESH_INTERNAL_H
#define FM_MESH_INTERNAL_H

#include "mesh/mesh.h"

/* Write bytes to path through "<path>.tmp" and a rename, so that a reader
 * never sees a partial file. */
fm_status fm_mesh_write_bytes_atomic(const char *path, const uint8_t *data, size_t size,
                                     fm_error *err);

#endif
