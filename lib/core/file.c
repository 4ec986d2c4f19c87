/* file.c: reading a whole file within a byte budget, and writing one so that
 * a crash leaves the old file or the new one, never a mix. Why each step of
 * the write: the temporary file keeps a reader (or a restart) from seeing
 * half a file; the fsync before the rename makes the data reach the disk
 * before the name points at it; the fsync of the folder makes the rename
 * itself survive a power cut. */
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* In the names of durable writers' temporary files: ".<name>" TMP_MARK
 * "<pid>.<n>". fm_file_remove_stale_temporaries looks for it. */
#define TMP_MARK ".fmtmp."

/* ------------------------------------------------------------- reading -- */

fm_status fm_file_read(const char *path, const char *what, size_t max_bytes, char **data,
                       size_t *size, fm_error *err)
{
    *data = NULL;
    *size = 0;
    if (!path) return fm_error_set(err, FM_ERR_INTERNAL, "fm_file_read: no path");
    /* the file as messages name it: "STL part.stl", or the path alone */
    char name[PATH_MAX + 64];
    snprintf(name, sizeof name, "%s%s%s", what ? what : "", what && *what ? " " : "", path);
    /* O_NONBLOCK: opening a FIFO for reading would wait for a writer. */
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", name, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return fm_error_set(err, FM_ERR_IO, "%s is not a regular file", name);
    }
    if ((uintmax_t)st.st_size > (uintmax_t)max_bytes) {
        close(fd);
        return fm_error_set_reason(err, FM_ERR_LIMIT, "too_large",
                                   "%s is %llu bytes, over the budget of %zu bytes", name,
                                   (unsigned long long)st.st_size, max_bytes);
    }
    /* Room for what fstat said, one byte more to see that the file grew,
     * and the NUL. */
    size_t cap = (size_t)st.st_size + 2, len = 0;
    char *buf = malloc(cap);
    fm_status rc = FM_OK;
    if (!buf) {
        close(fd);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", name);
    }
    for (;;) {
        if (len == cap - 1) {
            /* the file grew since fstat (or is in /proc): keep reading,
             * within the budget */
            if (len > max_bytes) {
                rc = fm_error_set_reason(err, FM_ERR_LIMIT, "too_large",
                                         "%s grew past the budget of %zu bytes while being read",
                                         name, max_bytes);
                break;
            }
            size_t room = 2 * len > len + 4096 ? 2 * len : len + 4096;
            if (max_bytes < SIZE_MAX - 2 && room > max_bytes + 1) room = max_bytes + 1;
            const size_t bigger = room + 1;
            char *nb = realloc(buf, bigger);
            if (!nb) {
                rc = fm_error_set(err, FM_ERR_LIMIT, "out of memory reading %s", name);
                break;
            }
            buf = nb;
            cap = bigger;
        }
        ssize_t r = read(fd, buf + len, cap - 1 - len);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) {
            rc = fm_error_set(err, FM_ERR_IO, "cannot read %s: %s", name, strerror(errno));
            break;
        }
        if (r == 0) break;
        len += (size_t)r;
    }
    close(fd);
    if (rc != FM_OK) {
        free(buf);
        return rc;
    }
    buf[len] = '\0';
    *data = buf;
    *size = len;
    return FM_OK;
}

/* ------------------------------------------------------------- writing -- */

static fm_status sync_dir(const char *dir, const char *who, fm_error *err)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return fm_error_set(err, FM_ERR_IO, "%s%scannot open folder %s: %s", who ? who : "",
                            who ? ": " : "", dir, strerror(errno));
    int rc = fsync(fd);
    int e = errno;
    close(fd);
    /* an fsync error means the rename may not survive a power cut: say so */
    if (rc != 0)
        return fm_error_set(err, FM_ERR_IO, "%s%sfsync failed on folder %s: %s", who ? who : "",
                            who ? ": " : "", dir, strerror(e));
    return FM_OK;
}

fm_status fm_file_sync_dir(const char *path, fm_error *err) { return sync_dir(path, NULL, err); }

typedef struct bytes {
    const unsigned char *p;
    size_t n;
} bytes;

int fm_file_write_all(int fd, const void *data, size_t size)
{
    const unsigned char *p = data;
    while (size > 0) {
        /* at most 1 GiB a call: Linux writes no more than about 2 GiB */
        ssize_t w = write(fd, p, size > ((size_t)1 << 30) ? ((size_t)1 << 30) : size);
        if (w < 0) {
            if (errno == EINTR) continue;
            return errno ? errno : EIO;
        }
        p += w;
        size -= (size_t)w;
    }
    return 0;
}

static int write_bytes(int fd, void *ctx)
{
    const bytes *b = ctx;
    return fm_file_write_all(fd, b->p, b->n);
}

fm_status fm_file_write_durable(const char *path, const char *what, const void *data,
                                size_t size, fm_error *err)
{
    bytes b = {data, size};
    return fm_file_write_durable_with(path, what, write_bytes, &b, NULL, err);
}

fm_status fm_file_write_durable_with(const char *path, const char *what, fm_file_writer writer,
                                     void *ctx, const char *previous, fm_error *err)
{
    static unsigned long counter;
    char dir[PATH_MAX], tmp[PATH_MAX], prevtmp[PATH_MAX], who[PATH_MAX + 16];
    if (!path || !*path || !writer)
        return fm_error_set(err, FM_ERR_INTERNAL, "fm_file_write_durable: no path");
    snprintf(who, sizeof who, "%s not saved", what && *what ? what : path);

    /* the folder ("." when none) and the base name */
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    size_t dlen = slash ? (size_t)(slash - path) : 1;
    if (slash && dlen == 0) dlen = 1; /* "/name" */
    if (!*base || dlen >= sizeof dir || strlen(base) > 200)
        return fm_error_set(err, FM_ERR_INPUT, "%s: \"%s\" is not a file path", who, path);
    memcpy(dir, slash ? path : ".", dlen);
    dir[dlen] = '\0';
    const unsigned long seq = __atomic_add_fetch(&counter, 1, __ATOMIC_RELAXED);
    if (snprintf(tmp, sizeof tmp, "%s/.%s" TMP_MARK "%ld.%lu", dir, base, (long)getpid(), seq) >=
            (int)sizeof tmp ||
        snprintf(prevtmp, sizeof prevtmp, "%s/.%s.prev" TMP_MARK "%ld.%lu", dir, base,
                 (long)getpid(), seq) >= (int)sizeof prevtmp)
        return fm_error_set(err, FM_ERR_INPUT, "%s: the path is too long", who);

    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        return fm_error_set(err, FM_ERR_IO, "%s: cannot create %s: %s", who, tmp, strerror(errno));
    fm_status rc = FM_OK;
    int e = writer(fd, ctx);
    if (e) {
        rc = fm_error_set(err, FM_ERR_IO, "%s: cannot write %s: %s", who, tmp, strerror(e));
        goto fail;
    }
    /* an fsync error means the data may not be on disk: not saved */
    if (fsync(fd) != 0) {
        rc = fm_error_set(err, FM_ERR_IO, "%s: fsync failed on %s: %s", who, tmp, strerror(errno));
        goto fail;
    }
    e = close(fd) != 0 ? errno : 0;
    fd = -1;
    if (e) {
        rc = fm_error_set(err, FM_ERR_IO, "%s: close failed on %s: %s", who, tmp, strerror(e));
        goto fail;
    }
    /* Keep the previous generation. A hard link plus rename replaces
     * previous atomically while path itself never disappears. */
    if (previous && access(path, F_OK) == 0) {
        if (link(path, prevtmp) == 0) {
            if (rename(prevtmp, previous) != 0) {
                rc = fm_error_set(err, FM_ERR_IO, "%s: cannot rename to %s: %s", who, previous,
                                  strerror(errno));
                unlink(prevtmp);
                goto fail;
            }
        } else if (rename(path, previous) != 0) { /* no hard links here */
            rc = fm_error_set(err, FM_ERR_IO, "%s: cannot rename to %s: %s", who, previous,
                              strerror(errno));
            goto fail;
        }
    }
    if (rename(tmp, path) != 0) {
        rc = fm_error_set(err, FM_ERR_IO, "%s: cannot rename to %s: %s", who, path,
                          strerror(errno));
        goto fail;
    }
    return sync_dir(dir, who, err);

fail:
    if (fd >= 0) close(fd);
    unlink(tmp);
    return rc;
}

fm_status fm_file_remove_stale_temporaries(const char *dir, size_t *removed, fm_error *err)
{
    if (removed) *removed = 0;
    DIR *d = opendir(dir);
    if (!d) return fm_error_set(err, FM_ERR_IO, "cannot open %s: %s", dir, strerror(errno));
    struct dirent *e;
    size_t count = 0;
    const long self = (long)getpid();
    while ((e = readdir(d)) != NULL) {
        const char *mark = strstr(e->d_name, TMP_MARK);
        if (e->d_name[0] != '.' || !mark) continue;
        char *end;
        const long pid = strtol(mark + strlen(TMP_MARK), &end, 10);
        if (end == mark + strlen(TMP_MARK) || *end != '.') continue;
        /* a writer that still runs may be in the middle of its write */
        if (pid == self) continue;
        if (pid > 0 && (kill((pid_t)pid, 0) == 0 || errno == EPERM)) continue;
        char full[PATH_MAX + 256];
        snprintf(full, sizeof full, "%s/%s", dir, e->d_name);
        if (unlink(full) == 0) count++;
    }
    closedir(d);
    if (removed) *removed = count;
    return FM_OK;
}
