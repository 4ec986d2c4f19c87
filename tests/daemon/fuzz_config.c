/* fuzz_config.c: libFuzzer target for frepmilld's config file parser
 * (fm_daemon_config_load) and its setter (fm_daemon_config_set, the path of
 * the --key value flags). The loader reads a path, so each input is written
 * to one unlinked temporary file, opened through /proc/self/fd. Any input
 * must give either a configuration within the documented ranges or an
 * error message, never a crash. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_input_file.h"

#include "config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void must_be_terminated(const char *s, size_t size)
{
    if (!memchr(s, '\0', size)) abort();
}

/* What frepmilld relies on after a successful load: every text is a
 * string, the addresses split, the numbers are within their ranges. */
static void check_config(const fm_daemon_config *c)
{
    char addr[64];
    unsigned port;
    must_be_terminated(c->listen, sizeof c->listen);
    must_be_terminated(c->state_dir, sizeof c->state_dir);
    must_be_terminated(c->modbus_listen, sizeof c->modbus_listen);
    must_be_terminated(c->token, sizeof c->token);
    must_be_terminated(c->log_file, sizeof c->log_file);
    must_be_terminated(c->viewer_dir, sizeof c->viewer_dir);
    must_be_terminated(c->demo_dir, sizeof c->demo_dir);
    must_be_terminated(c->live_stock, sizeof c->live_stock);
    must_be_terminated(c->live_tools, sizeof c->live_tools);
    if (fm_daemon_split_addr(c->listen, addr, sizeof addr, &port) != 0) abort();
    if (strcmp(c->modbus_listen, "off") != 0 &&
        fm_daemon_split_addr(c->modbus_listen, addr, sizeof addr, &port) != 0)
        abort();
    if (c->workers < 1 || c->workers > 256) abort();
    if (c->threads_per_job < 0 || c->threads_per_job > 1024) abort();
    if (c->log_level < 0 || c->log_level > 3) abort();
    if (!(c->snapshot_interval_s >= 0.1 && c->snapshot_interval_s <= 86400)) abort();
    if (!(c->publish_interval_s >= 0.05 && c->publish_interval_s <= 3600)) abort();
    if (!(c->max_request_mb > 0 && c->job_memory_mb >= 1)) abort();
    if (c->max_jobs < 1 || c->max_connections < 1 || c->max_connections_per_ip < 1) abort();
    if (c->request_deadline_ms < 100 || c->idle_timeout_s < 1) abort();
    if (!(c->demo_voxel >= 0.01 && c->live_voxel >= 0.01 && c->live_feed > 0)) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *input_path = fuzz_input_file("fuzz_config", data, size);

    fm_daemon_config cfg;
    char msg[1024];
    fm_daemon_config_default(&cfg);
    msg[0] = 'x';
    msg[sizeof msg - 1] = 'x';
    if (fm_daemon_config_load(&cfg, input_path, msg, sizeof msg) == 0)
        check_config(&cfg);
    else
        must_be_terminated(msg, sizeof msg);

    /* The same bytes as one flag: the key up to the first NUL or newline,
     * the value after it (argv strings hold anything but NUL). */
    char *copy = malloc(size + 2);
    if (!copy) return 0;
    memcpy(copy, data, size);
    copy[size] = copy[size + 1] = '\0';
    size_t k = 0;
    while (k < size && data[k] != '\n' && data[k] != '\0') k++;
    copy[k] = '\0';
    const char *key = copy, *value = k < size ? copy + k + 1 : copy + size + 1;
    fm_daemon_config_default(&cfg);
    if (fm_daemon_config_set(&cfg, key, value, msg, sizeof msg) == 0)
        check_config(&cfg);
    else
        must_be_terminated(msg, sizeof msg);
    free(copy);
    return 0;
}
