/* test_modbus_node.c: a Node Modbus master from the npm registry
 * (modbus-serial, pinned in tests/modbus/package-lock.json) writes commands
 * and live positions to a server with commands and live mode enabled, and
 * tries to write to a read-only one. This program checks what the client saw
 * (node_client.js prints it) and what the fake service recorded: a command
 * acts once per new sequence number, pause and resume arrive with their
 * argument, floats round-trip, and the read-only server refuses every write
 * with exception 02. deploy/install-deps.sh test installs the client into
 * tests/modbus/node_modules (the test never downloads); without node or
 * that folder the test skips (test_skip). */
#include <sys/stat.h>

#include "modbus/modbus_test_util.h"
#include "test.h"

static fm_modbus_server *start(mt_service *svc, int writable)
{
    fm_modbus_service iface = mt_service_iface(svc);
    fm_modbus_config cfg;
    fm_modbus_config_default(&cfg);
    cfg.port = 0;
    cfg.enable_commands = writable;
    cfg.enable_live = writable;
    fm_modbus_server *s = NULL;
    fm_error err;
    if (fm_modbus_server_start(&cfg, &iface, &s, &err) != FM_OK)
        fprintf(stderr, "%s\n", err.message);
    return s;
}

static const char *value_of(const char *out, const char *key)
{
    static char buf[512];
    const char *p = out;
    size_t klen = strlen(key);
    while (p && *p) {
        if (strncmp(p, key, klen) == 0 && p[klen] == ' ') {
            const char *v = p + klen + 1;
            size_t n = strcspn(v, "\n");
            if (n >= sizeof buf)
                n = sizeof buf - 1;
            memcpy(buf, v, n);
            buf[n] = 0;
            return buf;
        }
        p = strchr(p, '\n');
        if (p)
            p++;
    }
    return "";
}

int main(void)
{
    if (!mt_have_program("node"))
        return test_skip("modbus_node: node is not installed (Debian package nodejs)");
    struct stat st;
    if (stat("modbus/node_modules/modbus-serial/package.json", &st) != 0)
        return test_skip("modbus_node: tests/modbus/node_modules/modbus-serial is missing "
                         "(deploy/install-deps.sh test installs it with npm ci)");

    mt_service rw_svc, ro_svc;
    mt_service_init(&rw_svc);
    mt_service_init(&ro_svc);
    fm_modbus_server *rw = start(&rw_svc, 1), *ro = start(&ro_svc, 0);
    CHECK(rw && ro);
    if (!rw || !ro)
        return test_summary("modbus_node");
    char prw[16], pro[16];
    snprintf(prw, sizeof prw, "%u", (unsigned)fm_modbus_server_port(rw));
    snprintf(pro, sizeof pro, "%u", (unsigned)fm_modbus_server_port(ro));
    char *node[] = {"node", "modbus/node_client.js", prw, pro, NULL};
    static char out[16384];
    int rc = mt_run(node, NULL, out, sizeof out, 60000);
    CHECK(rc == 0);
    printf("%s", out);

    /* What the client saw. */
    CHECK(strcmp(value_of(out, "ack_after_repeat"), "1") == 0);
    CHECK(strcmp(value_of(out, "regs26_28"), "0 2 3") == 0); /* no error, slot 2, ack 3 */
    double f[7] = {0};
    CHECK(sscanf(value_of(out, "floats"), "%lf %lf %lf %lf %lf %lf %lf", &f[0], &f[1], &f[2], &f[3], &f[4], &f[5],
                 &f[6]) == 7);
    const double want[7] = {12.5, -3.25, 100.125, 42.75, 1234.5, 98765.25, 0.15625};
    for (int k = 0; k < 7; k++)
        CHECK(f[k] == want[k]); /* all exact in float32 */
    CHECK(strcmp(value_of(out, "live_written"), "1") == 0);
    CHECK(strcmp(value_of(out, "readonly_fc16"), "2") == 0);
    CHECK(strcmp(value_of(out, "readonly_fc06"), "2") == 0);
    CHECK(strcmp(value_of(out, "readonly_live"), "2") == 0);
    CHECK(strcmp(value_of(out, "readonly_read"), "1") == 0);

    /* What the daemon would have been asked: pause(7) once for sequence 1
     * (the repeats are ignored), resume(7) for 2, pause(9) for 3, then live
     * mode on and one position. */
    fm_modbus_server_stop(rw);
    fm_modbus_server_stop(ro);
    mt_call *c = rw_svc.calls;
    CHECK(rw_svc.ncalls == 5);
    if (rw_svc.ncalls == 5) {
        CHECK(c[0].kind == 'c' && c[0].command == FM_MODBUS_CMD_PAUSE && c[0].argument == 7);
        CHECK(c[1].kind == 'c' && c[1].command == FM_MODBUS_CMD_START && c[1].argument == 7);
        CHECK(c[2].kind == 'c' && c[2].command == FM_MODBUS_CMD_PAUSE && c[2].argument == 9);
        CHECK(c[3].kind == 'm' && c[3].command == 1);
        CHECK(c[4].kind == 'p' && c[4].xyz[0] == 10.5 && c[4].xyz[1] == -20.25 && c[4].xyz[2] == 5.125 &&
              c[4].tool == 6);
    }
    CHECK(ro_svc.ncalls == 0);
    mt_service_destroy(&rw_svc);
    mt_service_destroy(&ro_svc);
    return test_summary("modbus_node");
}
