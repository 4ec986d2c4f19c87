/* store.c: durable small files for the job store. Why each step: the
 * temporary file keeps a reader (or a restart) from seeing half a file; the
 * fsync before the rename makes the data reach the disk before the name
 * points at it; the fsync of the folder makes the rename itself survive a
 * power cut. A job is acknowledged only after all of it returned. */
#include "store.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
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

fm_status fm_store_fsync_dir(const char *path, fm_error *err)
{
    int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    int rc = fsync(fd);
    int e = errno;
    close(fd);
    if (rc != 0) return fm_error_set(err, FM_ERR_IO, "fsync %s: %s", path, strerror(e));
    return FM_OK;
}

fm_status fm_store_write_atomic(const char *dir, const char *name, const void *data, size_t size,
                                fm_error *err)
{
    char path[PATH_MAX], tmp[PATH_MAX];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path ||
        snprintf(tmp, sizeof tmp, "%s/%s.tmp", dir, name) >= (int)sizeof tmp)
        return fm_error_set(err, FM_ERR_IO, "path too long: %s/%s", dir, name);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
    if (fd < 0) return fm_error_set(err, FM_ERR_IO, "cannot create %s: %s", tmp, strerror(errno));
    const char *p = data;
    size_t left = size;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            int e = errno;
            close(fd);
            unlink(tmp);
            return fm_error_set(err, FM_ERR_IO, "cannot write %s: %s", tmp, strerror(e));
        }
        p += w;
        left -= (size_t)w;
    }
    if (fsync(fd) != 0) {
        int e = errno;
        close(fd);
        unlink(tmp);
        return fm_error_set(err, FM_ERR_IO, "fsync %s: %s", tmp, strerror(e));
    }
    if (close(fd) != 0) {
        unlink(tmp);
        return fm_error_set(err, FM_ERR_IO, "cannot write %s: %s", tmp, strerror(errno));
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        return fm_error_set(err, FM_ERR_IO, "cannot rename %s: %s", tmp, strerror(e));
    }
    return fm_store_fsync_dir(dir, err);
}

fm_status fm_store_read(const char *path, size_t max, char **data, size_t *size, fm_error *err)
{
    *data = NULL;
    *size = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || (size_t)st.st_size > max) {
        close(fd);
        return fm_error_set(err, FM_ERR_IO, "%s is not a regular file of at most %zu bytes", path,
                            max);
    }
    size_t n = (size_t)st.st_size;
    char *buf = malloc(n + 1);
    if (!buf) {
        close(fd);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", path);
    }
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        got += (size_t)r;
    }
    close(fd);
    if (got != n) {
        free(buf);
        return fm_error_set(err, FM_ERR_IO, "short read of %s", path);
    }
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return FM_OK;
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
