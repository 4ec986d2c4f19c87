/* store.h: the daemon's durable files: crash-safe small-file writes in a
 * folder (lib/core's fm_file_write_durable, which also writes the stock
 * snapshots) and the folder operations the job store needs. Reads with a
 * size cap are lib/core's fm_file_read. */
#ifndef FM_DAEMON_STORE_H
#define FM_DAEMON_STORE_H

#include <stddef.h>

#include "core/core.h"

/* Create path and its missing parents (mode 0750). */
fm_status fm_store_mkdirs(const char *path, fm_error *err);
/* Write dir/name whole with fm_file_write_durable: a crash at any point
 * leaves either the old file or the new one, never a mix. */
fm_status fm_store_write_atomic(const char *dir, const char *name, const void *data, size_t size,
                                fm_error *err);
/* Remove a folder and the files in it (one level: job folders have no
 * subfolders). */
fm_status fm_store_remove_dir(const char *path, fm_error *err);

#endif
