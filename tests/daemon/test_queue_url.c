/* test_queue_url.c: the Redis queue URL parser (fm_redis_url_parse) and the
 * queue settings of the daemon's config, against values written by hand. */
#include <string.h>

#include "config.h"
#include "queue_redis.h"
#include "test.h"

static void url_ok(const char *text, const char *host, unsigned port, const char *user,
                   const char *password, int db)
{
    fm_redis_url u;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_redis_url_parse(text, &u, &err) == FM_OK);
    CHECK(!strcmp(u.host, host));
    CHECK(u.port == port);
    CHECK(!strcmp(u.user, user));
    CHECK(!strcmp(u.password, password));
    CHECK(u.db == db);
}

static void url_bad(const char *text, const char *says)
{
    fm_redis_url u;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_redis_url_parse(text, &u, &err) == FM_ERR_INPUT);
    CHECK(strstr(err.message, says) != NULL);
}

int main(void)
{
    url_ok("redis://127.0.0.1", "127.0.0.1", 6379, "", "", 0);
    url_ok("redis://localhost:6380", "localhost", 6380, "", "", 0);
    url_ok("redis://:pw@h:1/3", "h", 1, "", "pw", 3);
    url_ok("redis://pw@h", "h", 6379, "", "pw", 0);
    url_ok("redis://alice:s3cr:et@redis.example:7000/", "redis.example", 7000, "alice", "s3cr:et", 0);
    url_ok("redis://[::1]:6390/1", "::1", 6390, "", "", 1);
    url_bad("rediss://h", "TLS");
    url_bad("http://h", "expected redis://");
    url_bad("redis://", "no host");
    url_bad("redis://h:0", "port");
    url_bad("redis://h:70000", "port");
    url_bad("redis://h:12x", "port");
    url_bad("redis://h/x", "database");
    url_bad("redis://[::1", "unterminated");
    url_bad("redis://h?x=1", "unexpected");
    url_bad("redis://h/1?x", "database");
    url_bad("redis://a b", "unexpected");

    fm_daemon_config cfg;
    fm_daemon_config_default(&cfg);
    CHECK(!strcmp(cfg.queue, "") && !strcmp(cfg.queue_stream, "frepmill:jobs"));
    CHECK(!strcmp(cfg.queue_group, "frepmilld") && cfg.queue_claim_s == 30);
    char msg[256];
    CHECK(fm_daemon_config_set(&cfg, "queue", "redis://h:1", msg, sizeof msg) == 0);
    CHECK(!strcmp(cfg.queue, "redis://h:1"));
    CHECK(fm_daemon_config_set(&cfg, "queue", "off", msg, sizeof msg) == 0);
    CHECK(fm_daemon_config_set(&cfg, "queue", "rediss://h", msg, sizeof msg) == -1);
    CHECK(strstr(msg, "queue:") && strstr(msg, "TLS"));
    CHECK(fm_daemon_config_set(&cfg, "queue_claim_s", "0", msg, sizeof msg) == -1);
    CHECK(fm_daemon_config_set(&cfg, "queue_claim_s", "2.5", msg, sizeof msg) == 0);
    CHECK(cfg.queue_claim_s == 2.5);
    return test_summary("queue_url");
}
