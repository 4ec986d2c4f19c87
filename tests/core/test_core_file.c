/* test_core_file.c: the bounded file reader (budgets, what is not a regular
 * file, files that grow while read) and the durable writer (old or new
 * content and no temporary file after a failure, the previous generation,
 * stale temporaries). */
#include "core/core.h"
#include "test.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char dir[64];

static void path_in(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s/%s", dir, name);
}

static void put_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    CHECK(f && fwrite(data, 1, n, f) == n);
    if (f) fclose(f);
}

/* The names in dir, sorted, joined by spaces. */
static void listing(char *out, size_t size)
{
    struct dirent **names;
    int n = scandir(dir, &names, NULL, alphasort);
    out[0] = '\0';
    for (int i = 0; i < n; i++) {
        if (strcmp(names[i]->d_name, ".") && strcmp(names[i]->d_name, "..")) {
            if (out[0]) strncat(out, " ", size - strlen(out) - 1);
            strncat(out, names[i]->d_name, size - strlen(out) - 1);
        }
        free(names[i]);
    }
    if (n >= 0) free(names);
}

static void reads(void)
{
    char p[128];
    char *data = (char *)1;
    size_t size = 99;
    fm_error err;

    /* the bytes as written, NUL bytes inside included, and a NUL after */
    const char text[] = "G0 X1\0Y2\n";
    path_in(p, sizeof p, "a.ngc");
    put_file(p, text, sizeof text - 1);
    CHECK(fm_file_read(p, NULL, 100, &data, &size, &err) == FM_OK);
    CHECK(size == sizeof text - 1 && data && memcmp(data, text, size) == 0 && data[size] == '\0');
    free(data);
    /* the budget is inclusive: exactly its size reads, one byte less refuses */
    CHECK(fm_file_read(p, NULL, sizeof text - 1, &data, &size, &err) == FM_OK);
    free(data);
    CHECK(fm_file_read(p, "program", sizeof text - 2, &data, &size, &err) == FM_ERR_LIMIT);
    CHECK(data == NULL && size == 0);
    CHECK(strcmp(err.reason, "too_large") == 0);
    CHECK_STR_CONTAINS(err.message, "program ");
    CHECK_STR_CONTAINS(err.message, p);
    CHECK_STR_CONTAINS(err.message, "is 9 bytes, over the budget of 8 bytes");

    /* an empty file is an empty string */
    path_in(p, sizeof p, "empty");
    put_file(p, "", 0);
    CHECK(fm_file_read(p, NULL, 0, &data, &size, &err) == FM_OK);
    CHECK(data && size == 0 && data[0] == '\0');
    free(data);

    /* a sparse file of 1 TiB over a budget one byte smaller: refused from
     * its size (reading or allocating it would not end here) */
    path_in(p, sizeof p, "huge");
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    CHECK(fd >= 0 && ftruncate(fd, (off_t)1 << 40) == 0);
    if (fd >= 0) close(fd);
    CHECK(fm_file_read(p, "STL", ((size_t)1 << 40) - 1, &data, &size, &err) == FM_ERR_LIMIT);
    CHECK(data == NULL);
    CHECK_STR_CONTAINS(err.message, "STL ");
    CHECK_STR_CONTAINS(err.message, "is 1099511627776 bytes, over the budget");
    unlink(p);

    /* missing: an I/O error that names the file and says why */
    path_in(p, sizeof p, "missing.stl");
    CHECK(fm_file_read(p, "STL", 100, &data, &size, &err) == FM_ERR_IO);
    CHECK(data == NULL);
    CHECK_STR_CONTAINS(err.message, "cannot open STL ");
    CHECK_STR_CONTAINS(err.message, "missing.stl: No such file or directory");

    /* a folder, a FIFO without a writer (opening it must not wait) and a
     * device are no files to read */
    CHECK(fm_file_read(dir, NULL, 100, &data, &size, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "is not a regular file");
    path_in(p, sizeof p, "fifo");
    CHECK(mkfifo(p, 0644) == 0);
    CHECK(fm_file_read(p, NULL, 100, &data, &size, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "is not a regular file");
    unlink(p);
    CHECK(fm_file_read("/dev/zero", NULL, 100, &data, &size, &err) == FM_ERR_IO);
    CHECK(data == NULL);
    CHECK_STR_CONTAINS(err.message, "/dev/zero is not a regular file");

    /* A file longer than fstat says (files in /proc say 0 bytes): read to
     * its end, and refused when it passes the budget while read. */
    CHECK(fm_file_read("/proc/self/status", NULL, 1 << 20, &data, &size, &err) == FM_OK);
    CHECK(data && size > 100 && strlen(data) == size);
    if (data) CHECK(strncmp(data, "Name:", 5) == 0);
    free(data);
    CHECK(fm_file_read("/proc/self/status", NULL, 10, &data, &size, &err) == FM_ERR_LIMIT);
    CHECK(data == NULL && size == 0);
    CHECK(strcmp(err.reason, "too_large") == 0);
    CHECK_STR_CONTAINS(err.message, "grew past the budget of 10 bytes while being read");

    path_in(p, sizeof p, "a.ngc");
    unlink(p);
    path_in(p, sizeof p, "empty");
    unlink(p);
}

static void check_content(const char *path, const char *want)
{
    char *data = NULL;
    size_t size = 0;
    fm_error err;
    CHECK(fm_file_read(path, NULL, 1 << 20, &data, &size, &err) == FM_OK);
    CHECK(data && strcmp(data, want) == 0);
    free(data);
}

typedef struct halfway {
    const char *text;
    int fail_errno;
} halfway;

/* Writes the text, then fails as a full disk would. */
static int write_then_fail(int fd, void *ctx)
{
    const halfway *h = ctx;
    if (write(fd, h->text, strlen(h->text)) != (ssize_t)strlen(h->text)) return errno;
    return h->fail_errno;
}

static void writes(void)
{
    char p[128], prev[140], names[512];
    fm_error err;

    path_in(p, sizeof p, "job.json");
    CHECK(fm_file_write_durable(p, NULL, "old", 3, &err) == FM_OK);
    check_content(p, "old");
    listing(names, sizeof names);
    CHECK(strcmp(names, "job.json") == 0);

    /* a writer that fails halfway: the old content, no temporary file */
    halfway h = {"new and long", ENOSPC};
    CHECK(fm_file_write_durable_with(p, "job", write_then_fail, &h, NULL, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "job not saved: cannot write ");
    CHECK_STR_CONTAINS(err.message, strerror(ENOSPC));
    check_content(p, "old");
    listing(names, sizeof names);
    CHECK(strcmp(names, "job.json") == 0);

    /* the file size limit reached in write(2) itself (EFBIG): the same */
    struct rlimit old_limit, small = {4, 4};
    signal(SIGXFSZ, SIG_IGN);
    CHECK(getrlimit(RLIMIT_FSIZE, &old_limit) == 0);
    small.rlim_max = old_limit.rlim_max;
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0);
    fm_status st = fm_file_write_durable(p, NULL, "0123456789", 10, &err);
    CHECK(setrlimit(RLIMIT_FSIZE, &old_limit) == 0);
    CHECK(st == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, " not saved: cannot write ");
    CHECK_STR_CONTAINS(err.message, strerror(EFBIG));
    check_content(p, "old");
    listing(names, sizeof names);
    CHECK(strcmp(names, "job.json") == 0);

    /* the rename fails (a folder holds the name): no temporary file */
    char sub[128];
    path_in(sub, sizeof sub, "taken");
    CHECK(mkdir(sub, 0755) == 0);
    CHECK(fm_file_write_durable(sub, "snapshot", "x", 1, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "snapshot not saved: cannot rename to ");
    listing(names, sizeof names);
    CHECK(strcmp(names, "job.json taken") == 0);
    rmdir(sub);

    /* a folder that is not there: nothing created, the path in the message */
    CHECK(fm_file_write_durable("/nonexistent-dir/x.vdb", NULL, "x", 1, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "/nonexistent-dir/x.vdb not saved: cannot create ");

    /* the previous generation is kept, and the new content takes the name */
    snprintf(prev, sizeof prev, "%s.prev", p);
    halfway ok = {"new", 0};
    CHECK(fm_file_write_durable_with(p, NULL, write_then_fail, &ok, prev, &err) == FM_OK);
    check_content(p, "new");
    check_content(prev, "old");
    listing(names, sizeof names);
    CHECK(strcmp(names, "job.json job.json.prev") == 0);
    unlink(prev);

    /* a bare name is in the current folder */
    char cwd[256];
    CHECK(getcwd(cwd, sizeof cwd) != NULL);
    CHECK(chdir(dir) == 0);
    CHECK(fm_file_write_durable("here.txt", NULL, "here", 4, &err) == FM_OK);
    CHECK(chdir(cwd) == 0);
    path_in(p, sizeof p, "here.txt");
    check_content(p, "here");
    unlink(p);

    CHECK(fm_file_sync_dir(dir, &err) == FM_OK);
    CHECK(fm_file_sync_dir("/nonexistent-dir", &err) == FM_ERR_IO);
}

/* Temporary files of a writer that died go; those of a living one stay. */
static void stale_temporaries(void)
{
    pid_t child = fork();
    if (child == 0) _exit(0);
    CHECK(child > 0 && waitpid(child, NULL, 0) == child);
    char dead[160], alive[160], other[160];
    snprintf(dead, sizeof dead, "%s/.job.json.fmtmp.%ld.1", dir, (long)child);
    snprintf(alive, sizeof alive, "%s/.job.json.fmtmp.%ld.1", dir, (long)getpid());
    snprintf(other, sizeof other, "%s/.job.json.fmtmp.x.1", dir); /* no pid: not ours */
    put_file(dead, "d", 1);
    put_file(alive, "a", 1);
    put_file(other, "o", 1);
    size_t removed = 99;
    fm_error err;
    CHECK(fm_file_remove_stale_temporaries(dir, &removed, &err) == FM_OK);
    CHECK(removed == 1);
    CHECK(access(dead, F_OK) != 0 && access(alive, F_OK) == 0 && access(other, F_OK) == 0);
    unlink(alive);
    unlink(other);
    CHECK(fm_file_remove_stale_temporaries("/nonexistent-dir", &removed, &err) == FM_ERR_IO);
    CHECK(removed == 0);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/fm_core_file_XXXXXX");
    if (!mkdtemp(dir)) return test_skip("cannot create a folder in /tmp");
    reads();
    writes();
    stale_temporaries();
    char p[128];
    path_in(p, sizeof p, "job.json");
    unlink(p);
    rmdir(dir);
    return test_summary("core_file");
}
