/* store.c: the job store's folders and its durable small files (written by
 * lib/core's durable writer: temporary file, fsync, rename, fsync of the
 * folder). A job is acknowledged only after all of it returned. */
#include "store.h"

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

fm_status fm_store_mkdirs(const char *path, fm_error *err)
{
    char buf[PATH_MAX];
    if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf)
        return fm_error_set(err, FM_ERR_IO, "path too long: %s", path);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/') continue;
        *p = '\0';
        if (mkdir(buf, 0750) != 0 && errno != EEXIST)
            return fm_error_set(err, FM_ERR_IO, "cannot create %s: %s", buf, strerror(errno));
        *p = '/';
    }
    if (mkdir(buf, 0750) != 0 && errno != EEXIST)
        return fm_error_set(err, FM_ERR_IO, "cannot create %s: %s", buf, strerror(errno));
    struct stat st;
    if (stat(buf, &st) != 0 || !S_ISDIR(st.st_mode))
        return fm_error_set(err, FM_ERR_IO, "%s is not a folder", buf);
    return FM_OK;
}

fm_status fm_store_write_atomic(const char *dir, const char *name, const void *data, size_t size,
                                fm_error *err)
{
    char path[PATH_MAX];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path)
        return fm_error_set(err, FM_ERR_IO, "path too long: %s/%s", dir, name);
    return fm_file_write_durable(path, NULL, data, size, err);
}

fm_status fm_store_remove_dir(const char *path, fm_error *err)
{
    DIR *d = opendir(path);
    if (!d) {
        if (errno == ENOENT) return FM_OK;
        return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    }
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char file[PATH_MAX];
        if (snprintf(file, sizeof file, "%s/%s", path, e->d_name) < (int)sizeof file)
            unlink(file);
    }
    closedir(d);
    if (rmdir(path) != 0)
        return fm_error_set(err, FM_ERR_IO, "cannot remove %s: %s", path, strerror(errno));
    return FM_OK;
}
