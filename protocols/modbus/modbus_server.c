/* modbus_server.c: the Modbus/TCP socket layer. One thread runs a poll()
 * loop over non-blocking sockets; each connection keeps its own partial frame,
 * so a client that trickles bytes, pipelines requests or stops reading costs
 * the others nothing: the loop only ever handles complete frames and never
 * waits on one socket. The engine (modbus_engine.c) does the protocol. */
#include "protocols/modbus/modbus_internal.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* Room for two replies: enough to answer a pipelined request while the
 * previous reply is still in the kernel; beyond that the connection is not
 * read until the client reads (back-pressure instead of unbounded memory). */
#define TX_CAPACITY (2 * FM_MODBUS_MAX_ADU)
#define MAX_ACCEPTS_PER_ROUND 64
#define HARD_MAX_CONNECTIONS 1024

typedef struct connection {
    int fd; /* -1 when the slot is free */
    uint8_t rx[FM_MODBUS_MAX_ADU];
    size_t rx_len;
    uint8_t tx[TX_CAPACITY];
    size_t tx_len;
    int64_t last_progress_ms; /* last byte received or sent */
    int64_t frame_start_ms;   /* first byte of the frame now in rx; 0 = none */
} connection;

struct fm_modbus_server {
    fm_modbus_config cfg;
    fm_modbus_engine engine;
    int listen_fd;
    int wake_pipe[2];
    uint16_t port;
    pthread_t thread;
    atomic_int stop;
    int max_connections;
    connection *conns;
    struct pollfd *pfds;
    int *pfd_conn; /* pfds index -> connection index */
    int64_t accept_paused_until_ms;
};

static int64_t monotonic_ms(void) { return (int64_t)(fm_clock_monotonic_s() * 1000); }

static void server_log(const fm_modbus_server *s, int level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void server_log(const fm_modbus_server *s, int level, const char *fmt, ...)
{
    if (!s->cfg.log)
        return;
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    s->cfg.log(s->cfg.log_ctx, level, msg);
}

void fm_modbus_config_default(fm_modbus_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->listen_addr, sizeof cfg->listen_addr, "127.0.0.1");
    cfg->port = 1502;
    cfg->word_order = FM_MODBUS_WORDS_ABCD;
    cfg->max_connections = 16;
    cfg->idle_timeout_ms = 60000;
    cfg->frame_timeout_ms = 2000;
}

static int set_nonblocking(int fd)
{
    int flags = fcntl(fd, F_GETFL, 0);
    return flags < 0 ? -1 : fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

/* abortive: reset instead of FIN. A client dropped for misbehaving (deadline,
 * malformed stream) may not be reading; a graceful close would leave the
 * kernel holding its unsent replies in FIN-WAIT for minutes. */
static void conn_close(fm_modbus_server *s, connection *c, const char *why, int abortive)
{
    server_log(s, FM_MODBUS_LOG_DEBUG, "modbus: closing connection %d: %s", c->fd, why);
    if (abortive) {
        struct linger lg = {1, 0};
        setsockopt(c->fd, SOL_SOCKET, SO_LINGER, &lg, sizeof lg);
    }
    close(c->fd);
    c->fd = -1;
    c->rx_len = 0;
    c->tx_len = 0;
    c->frame_start_ms = 0;
}

/* Send what is queued. Returns 0, or -1 when the connection is gone. */
static int conn_flush(fm_modbus_server *s, connection *c, int64_t now)
{
    while (c->tx_len > 0) {
        ssize_t n = send(c->fd, c->tx, c->tx_len, MSG_NOSIGNAL);
        if (n > 0) {
            memmove(c->tx, c->tx + n, c->tx_len - (size_t)n);
            c->tx_len -= (size_t)n;
            c->last_progress_ms = now;
        } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            return 0;
        } else if (n < 0 && errno == EINTR) {
            continue;
        } else {
            conn_close(s, c, "send failed", 1);
            return -1;
        }
    }
    return 0;
}

/* Answer every complete frame in rx while there is room for the reply. */
static int conn_process(fm_modbus_server *s, connection *c, int64_t now)
{
    while (c->rx_len > 0) {
        int total = fm_modbus_frame_length(c->rx, c->rx_len);
        if (total < 0) {
            conn_close(s, c, "not a Modbus/TCP header", 1);
            return -1;
        }
        if (total == 0 || c->rx_len < (size_t)total) {
            if (c->frame_start_ms == 0)
                c->frame_start_ms = now;
            return 0;
        }
        if (c->tx_len + FM_MODBUS_MAX_ADU > TX_CAPACITY)
            return 0; /* resumed from conn_flush's caller once the client reads */
        size_t n = fm_modbus_engine_handle(&s->engine, c->rx, (size_t)total, c->tx + c->tx_len);
        if (n == 0) {
            conn_close(s, c, "malformed frame", 1);
            return -1;
        }
        c->tx_len += n;
        c->rx_len -= (size_t)total;
        memmove(c->rx, c->rx + total, c->rx_len);
        c->frame_start_ms = c->rx_len > 0 ? now : 0;
        if (conn_flush(s, c, now) < 0)
            return -1;
    }
    return 0;
}

static void conn_read(fm_modbus_server *s, connection *c, int64_t now)
{
    /* Never more than the free part of the 260-byte frame buffer. */
    ssize_t n = recv(c->fd, c->rx + c->rx_len, sizeof c->rx - c->rx_len, 0);
    if (n == 0) {
        conn_close(s, c, "peer closed", 0);
        return;
    }
    if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
            conn_close(s, c, "recv failed", 1);
        return;
    }
    c->rx_len += (size_t)n;
    c->last_progress_ms = now;
    conn_process(s, c, now);
}

static void accept_clients(fm_modbus_server *s, int64_t now)
{
    for (int round = 0; round < MAX_ACCEPTS_PER_ROUND; round++) {
        int fd = accept(s->listen_fd, NULL, NULL);
        if (fd < 0) {
            /* Out of descriptors the pending connection stays queued and the
             * listener stays readable: stop polling it for a while instead of
             * spinning. Anything else (EAGAIN, ECONNABORTED) just returns. */
            if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
                server_log(s, FM_MODBUS_LOG_ERROR, "modbus: accept: %s", strerror(errno));
                s->accept_paused_until_ms = now + 100;
            }
            return;
        }
        connection *slot = NULL;
        for (int i = 0; i < s->max_connections; i++) {
            if (s->conns[i].fd < 0) {
                slot = &s->conns[i];
                break;
            }
        }
        if (!slot || set_nonblocking(fd) < 0) {
            server_log(s, FM_MODBUS_LOG_WARN, "modbus: connection limit (%d) reached, refusing a client",
                       s->max_connections);
            close(fd);
            continue;
        }
        int one = 1;
        /* Replies are single small segments; Nagle would only add latency. */
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        slot->fd = fd;
        slot->rx_len = 0;
        slot->tx_len = 0;
        slot->last_progress_ms = now;
        slot->frame_start_ms = 0;
    }
}

static void check_deadlines(fm_modbus_server *s, int64_t now)
{
    for (int i = 0; i < s->max_connections; i++) {
        connection *c = &s->conns[i];
        if (c->fd < 0)
            continue;
        if (s->cfg.frame_timeout_ms > 0 && c->frame_start_ms != 0 &&
            now - c->frame_start_ms > s->cfg.frame_timeout_ms)
            conn_close(s, c, "frame deadline", 1);
        else if (s->cfg.idle_timeout_ms > 0 && now - c->last_progress_ms > s->cfg.idle_timeout_ms)
            conn_close(s, c, "idle deadline", 1);
    }
}

static void *server_thread(void *arg)
{
    fm_modbus_server *s = arg;
    while (!atomic_load(&s->stop)) {
        int64_t now = monotonic_ms();
        int timeout = fm_modbus_engine_tick(&s->engine, now);
        check_deadlines(s, now);

        int n = 0;
        s->pfds[n].fd = s->wake_pipe[0];
        s->pfds[n].events = POLLIN;
        s->pfd_conn[n++] = -1;
        s->pfds[n].fd = now < s->accept_paused_until_ms ? -1 : s->listen_fd; /* -1: ignored by poll */
        s->pfds[n].events = POLLIN;
        s->pfd_conn[n++] = -1;
        for (int i = 0; i < s->max_connections; i++) {
            connection *c = &s->conns[i];
            if (c->fd < 0)
                continue;
            short ev = 0;
            /* Not read while a reply waits: the client must read first. */
            if (c->tx_len == 0)
                ev |= POLLIN;
            else
                ev |= POLLOUT;
            s->pfds[n].fd = c->fd;
            s->pfds[n].events = ev;
            s->pfd_conn[n++] = i;
        }
        if (timeout < 0)
            timeout = 0;
        if (timeout > 100)
            timeout = 100;
        int ready = poll(s->pfds, (nfds_t)n, timeout);
        if (ready <= 0)
            continue; /* timeout or EINTR: the top of the loop ticks */
        now = monotonic_ms();
        fm_modbus_engine_tick(&s->engine, now);
        if (s->pfds[0].revents) {
            char buf[16];
            while (read(s->wake_pipe[0], buf, sizeof buf) > 0) {
            }
        }
        for (int k = 2; k < n; k++) {
            short re = s->pfds[k].revents;
            connection *c = &s->conns[s->pfd_conn[k]];
            if (!re || c->fd < 0)
                continue;
            if (re & POLLOUT) {
                if (conn_flush(s, c, now) < 0)
                    continue;
                if (c->tx_len == 0 && conn_process(s, c, now) < 0)
                    continue;
            }
            if (re & (POLLIN | POLLHUP | POLLERR))
                conn_read(s, c, now);
        }
        if (s->pfds[1].revents & POLLIN)
            accept_clients(s, now);
    }
    return NULL;
}

static void server_free(fm_modbus_server *s)
{
    if (!s)
        return;
    if (s->conns) {
        for (int i = 0; i < s->max_connections; i++)
            if (s->conns[i].fd >= 0)
                close(s->conns[i].fd);
    }
    if (s->listen_fd >= 0)
        close(s->listen_fd);
    if (s->wake_pipe[0] >= 0)
        close(s->wake_pipe[0]);
    if (s->wake_pipe[1] >= 0)
        close(s->wake_pipe[1]);
    free(s->conns);
    free(s->pfds);
    free(s->pfd_conn);
    free(s);
}

fm_status fm_modbus_server_start(const fm_modbus_config *cfg, const fm_modbus_service *svc,
                                 fm_modbus_server **out, fm_error *err)
{
    if (out)
        *out = NULL;
    if (!cfg || !svc || !out || !svc->read_status)
        return fm_error_set(err, FM_ERR_INPUT, "modbus: missing configuration, service or read_status");
    if (cfg->max_connections < 1 || cfg->max_connections > HARD_MAX_CONNECTIONS)
        return fm_error_set(err, FM_ERR_INPUT, "modbus: max_connections must be 1..%d, not %d",
                            HARD_MAX_CONNECTIONS, cfg->max_connections);
    if (cfg->enable_commands && !svc->command)
        return fm_error_set(err, FM_ERR_INPUT, "modbus: commands enabled but the service has no command()");
    if (cfg->enable_commands && cfg->watchdog_ms > 0 && !svc->watchdog_expired)
        return fm_error_set(err, FM_ERR_INPUT,
                            "modbus: watchdog enabled but the service has no watchdog_expired()");
    if (cfg->enable_live && (!svc->live_position || !svc->live_mode))
        return fm_error_set(err, FM_ERR_INPUT,
                            "modbus: live mode enabled but the service lacks live_position() or live_mode()");

    struct sockaddr_in addr;
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons(cfg->port);
    if (inet_pton(AF_INET, cfg->listen_addr, &addr.sin_addr) != 1)
        return fm_error_set(err, FM_ERR_INPUT, "modbus: listen address '%.63s' is not a numeric IPv4 address",
                            cfg->listen_addr);

    fm_modbus_server *s = calloc(1, sizeof *s);
    if (!s)
        return fm_error_set(err, FM_ERR_LIMIT, "modbus: out of memory");
    s->cfg = *cfg;
    s->listen_fd = -1;
    s->wake_pipe[0] = s->wake_pipe[1] = -1;
    s->max_connections = cfg->max_connections;
    atomic_init(&s->stop, 0);
    s->conns = calloc((size_t)s->max_connections, sizeof *s->conns);
    s->pfds = calloc((size_t)s->max_connections + 2, sizeof *s->pfds);
    s->pfd_conn = calloc((size_t)s->max_connections + 2, sizeof *s->pfd_conn);
    if (!s->conns || !s->pfds || !s->pfd_conn) {
        server_free(s);
        return fm_error_set(err, FM_ERR_LIMIT, "modbus: out of memory");
    }
    for (int i = 0; i < s->max_connections; i++)
        s->conns[i].fd = -1;

    if (pipe(s->wake_pipe) < 0 || set_nonblocking(s->wake_pipe[0]) < 0 ||
        set_nonblocking(s->wake_pipe[1]) < 0) {
        int e = errno;
        server_free(s);
        return fm_error_set(err, FM_ERR_IO, "modbus: pipe: %s", strerror(e));
    }
    s->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    if (s->listen_fd < 0 || setsockopt(s->listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0 ||
        bind(s->listen_fd, (struct sockaddr *)&addr, sizeof addr) < 0 || listen(s->listen_fd, 64) < 0 ||
        set_nonblocking(s->listen_fd) < 0) {
        int e = errno;
        server_free(s);
        return fm_error_set(err, FM_ERR_IO, "modbus: cannot listen on %.63s:%u: %s", cfg->listen_addr,
                            (unsigned)cfg->port, strerror(e));
    }
    struct sockaddr_in bound;
    socklen_t blen = sizeof bound;
    if (getsockname(s->listen_fd, (struct sockaddr *)&bound, &blen) < 0) {
        int e = errno;
        server_free(s);
        return fm_error_set(err, FM_ERR_IO, "modbus: getsockname: %s", strerror(e));
    }
    s->port = ntohs(bound.sin_port);
    fm_modbus_engine_init(&s->engine, cfg, svc, monotonic_ms());

    int rc = pthread_create(&s->thread, NULL, server_thread, s);
    if (rc != 0) {
        server_free(s);
        return fm_error_set(err, FM_ERR_INTERNAL, "modbus: cannot start the server thread: %s", strerror(rc));
    }
    server_log(s, FM_MODBUS_LOG_INFO, "modbus: listening on %s:%u", cfg->listen_addr, (unsigned)s->port);
    *out = s;
    return FM_OK;
}

uint16_t fm_modbus_server_port(const fm_modbus_server *server)
{
    return server ? server->port : 0;
}

void fm_modbus_server_stop(fm_modbus_server *server)
{
    if (!server)
        return;
    atomic_store(&server->stop, 1);
    char b = 1;
    /* A full pipe already means a wake-up is pending. */
    if (write(server->wake_pipe[1], &b, 1) < 0) {
    }
    pthread_join(server->thread, NULL);
    server_free(server);
}
