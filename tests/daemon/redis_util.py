"""redis_util.py: a minimal Redis client (RESP2 over a socket) and a
redis-server started on a free loopback port, for the fleet tests and the
fleet bench. No Python package is needed beyond the standard library."""
import os
import shutil
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from fm_skip import skip  # noqa: E402  (the tests' skip rule: CI=true or CI=1 never skips)


class RedisError(Exception):
    pass


class Redis:
    def __init__(self, port, timeout=10):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
        self.file = self.sock.makefile("rb")

    def close(self):
        self.file.close()
        self.sock.close()

    def __call__(self, *args):
        out = [b"*%d\r\n" % len(args)]
        for a in args:
            a = a if isinstance(a, bytes) else str(a).encode()
            out.append(b"$%d\r\n%s\r\n" % (len(a), a))
        self.sock.sendall(b"".join(out))
        return self._read()

    def _read(self):
        line = self.file.readline()
        if not line:
            raise RedisError("connection closed")
        kind, rest = line[:1], line[1:-2]
        if kind == b"+":
            return rest.decode()
        if kind == b"-":
            raise RedisError(rest.decode())
        if kind == b":":
            return int(rest)
        if kind == b"$":
            n = int(rest)
            if n < 0:
                return None
            data = self.file.read(n + 2)
            return data[:-2]
        if kind == b"*":
            n = int(rest)
            if n < 0:
                return None
            return [self._read() for _ in range(n)]
        raise RedisError("bad reply %r" % line)


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def need_redis_server():
    """The path of redis-server; exits 77 (skip) when it is missing, or 1
    under CI=true or CI=1, where nothing may skip (fm_skip)."""
    path = shutil.which("redis-server")
    if path:
        return path
    skip("redis-server is not installed (Debian package redis-server; deploy/install-deps.sh test)")


class RedisServer:
    """redis-server on 127.0.0.1:port with an append-only file in data_dir,
    so that a stop and a restart keep every stream and hash."""

    def __init__(self, binary, data_dir, port=None):
        self.binary = binary
        self.data_dir = data_dir
        self.port = port or free_port()
        os.makedirs(data_dir, exist_ok=True)
        self.proc = None
        self.start()

    def start(self):
        log = open(os.path.join(self.data_dir, "redis.log"), "ab")
        self.proc = subprocess.Popen(
            [self.binary, "--port", str(self.port), "--bind", "127.0.0.1", "--dir", self.data_dir,
             "--appendonly", "yes", "--appendfsync", "always", "--save", "",
             "--protected-mode", "yes"],
            stdout=log, stderr=log)
        log.close()
        deadline = time.time() + 20
        while time.time() < deadline:
            try:
                r = Redis(self.port, timeout=2)
                if r("PING") == "PONG":
                    r.close()
                    return
                r.close()
            except (OSError, RedisError):
                pass
            if self.proc.poll() is not None:
                raise RuntimeError("redis-server exited with %d" % self.proc.returncode)
            time.sleep(0.05)
        raise RuntimeError("redis-server did not answer within 20 s")

    def stop(self):
        """A clean stop (SIGTERM: redis-server flushes its append-only file)."""
        if self.proc and self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(timeout=30)

    def client(self):
        return Redis(self.port)
