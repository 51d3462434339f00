"""A `tactip serve` under a flood of half-open connections, shared by the plain-HTTP and browser tests."""

from __future__ import annotations

import contextlib
import resource
import socket
import subprocess
import sys


@contextlib.contextmanager
def served_under_a_half_open_flood(db, token: str, *, connections: int = 400, open_files: int = 256):
    """Serve ``db`` with ``token`` at ``ulimit -n open_files``, open ``connections`` that each send half a
    request head and never the rest, and yield the page's URL (ending in ``/``). On exit the flood is closed,
    the server stopped, and its console must hold no 'Too many open files' and no traceback."""
    serve = subprocess.Popen([sys.executable, "-m", "tactip.cli", "serve", "--db", str(db), "--port", "0",
                              "--token", token], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_NOFILE, (open_files, open_files)))
    flood = []
    try:
        url = serve.stdout.readline().split(" on ")[1].split()[0].split("?")[0]
        port = int(url.rstrip("/").rsplit(":", 1)[1])
        for _ in range(connections):
            s = socket.socket()
            s.setblocking(False)
            s.connect_ex(("127.0.0.1", port))
            flood.append(s)
        for s in flood:
            try:
                s.send(b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n")             # and never the rest
            except OSError:
                pass                                                            # not accepted yet, or dropped
        yield url
    finally:
        for s in flood:
            s.close()
        serve.terminate()
        _, err = serve.communicate(timeout=20)
    assert "Too many open files" not in err and "Traceback" not in err, err
