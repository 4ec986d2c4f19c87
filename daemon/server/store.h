/* store.h: the daemon's durable files: crash-safe small-file writes (temp
 * file, fsync, rename, fsync of the folder), reads with a size cap, and the
 * folder operations the job store needs. Stock snapshots have their own
 * crash-safe writer in lib/stock (fm_stock_save). */
#ifndef FM_DAEMON_STORE_H
#define FM_DAEMON_STORE_H

#include <stddef.h>

#include "core/core.h"

/* Create path and its missing parents (mode 0750). */
fm_status fm_store_mkdirs(const char *path, fm_error *err);
/* fsync a folder, so that a rename or a new entry in it is durable. */
fm_status fm_store_fsync_dir(const char *path, fm_error *err);
/* Write dir/name whole: dir/name.tmp is written and fsynced, renamed over
 * dir/name, and dir is fsynced. A crash at any point leaves either the old
 * file or the new one, never a mix. */
fm_status fm_store_write_atomic(const char *dir, const char *name, const void *data, size_t size,
                                fm_error *err);
/* Read a whole file of at most max bytes into a NUL-terminated malloc'd
 * buffer. */
fm_status fm_store_read(const char *path, size_t max, char **data, size_t *size, fm_error *err);
/* Remove a folder and the files in it (one level: job folders have no
 * subfolders). */
fm_status fm_store_remove_dir(const char *path, fm_error *err);

#endif
