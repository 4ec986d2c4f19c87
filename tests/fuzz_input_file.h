/* fuzz_input_file.h: for the libFuzzer targets whose parser reads a path
 * (config files, machine files, STL, snapshots): each input is written to
 * one temporary file, unlinked at once so that nothing is left behind
 * however the run ends, and read back through /proc/self/fd. */
#ifndef FM_TESTS_FUZZ_INPUT_FILE_H
#define FM_TESTS_FUZZ_INPUT_FILE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* Write data as the whole content of the target's input file and return
 * its path. The file lives in $TMPDIR if set, else in /dev/shm (tmpfs: on
 * ext4 the truncate and write of each input cost 15 times a small parse),
 * else in /tmp; name is the file name's prefix. Aborts when it cannot. */
static inline const char *fuzz_input_file(const char *name, const uint8_t *data, size_t size)
{
    static char path[64];
    static int fd = -1;
    if (fd < 0) {
        const char *dir = getenv("TMPDIR");
        const char *dirs[] = {dir && *dir ? dir : "/dev/shm", "/tmp"};
        char tmp[1024];
        for (int i = 0; i < 2 && fd < 0; i++) {
            snprintf(tmp, sizeof tmp, "%s/%s.XXXXXX", dirs[i], name);
            fd = mkstemp(tmp);
        }
        if (fd < 0) abort();
        unlink(tmp);
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != (ssize_t)size) abort();
    return path;
}

#endif
