"""Real services for the tests: a throwaway PostgreSQL cluster, and Debian's headless Chromium.

`make services` installs Debian's ``postgresql`` and ``chromium`` when they are missing (Playwright
drives Chromium over its own protocol: no chromedriver); where that was not possible the tests that
need them skip and say so (`find_postgres_bin`, `find_chromium` return None).

`PostgresCluster` is a cluster of its own: ``initdb`` into a temporary folder, ``pg_ctl`` start on a
free port of 127.0.0.1 (and a socket in that folder), trust authentication for its one user, no
fsync (throwaway data). PostgreSQL refuses to run as root: as root the cluster runs as the
``postgres`` system user (``runuser``).
"""

from __future__ import annotations

import glob
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
from pathlib import Path

SKIP_POSTGRES = ("PostgreSQL is not installed (Debian's postgresql package: run `make services` as root, "
                 "or apt-get install postgresql)")
SKIP_CHROMIUM = ("Chromium is not installed (Debian's chromium package: run `make services` as root, "
                 "or apt-get install chromium)")


def find_postgres_bin() -> Path | None:
    """The folder of ``initdb`` and ``pg_ctl`` (Debian keeps them out of PATH), or None."""
    for name in ("initdb", "pg_ctl"):
        if shutil.which(name) is None:
            break
    else:
        return Path(shutil.which("initdb")).resolve().parent
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), key=lambda p: int(Path(p).parts[4]))
    return Path(found[-1]).parent if found else None


def find_chromium() -> str | None:
    """Path of Debian's Chromium, or None."""
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


def free_port() -> int:
    """A TCP port of 127.0.0.1 that nothing listens on (just now)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class PostgresCluster:
    """A throwaway PostgreSQL server on 127.0.0.1; `url` names a database, `create_database` makes one."""

    USER = "tactip"

    def __init__(self, bin_dir: Path):
        self.bin_dir = Path(bin_dir)
        self.root = Path(tempfile.mkdtemp(prefix="tactip-pg-"))
        self.data = self.root / "data"
        self.port = free_port()
        self._as = []
        if os.geteuid() == 0:
            user = pwd.getpwnam("postgres")
            os.chown(self.root, user.pw_uid, user.pw_gid)
            self._as = ["runuser", "-u", "postgres", "--"]
        self._run([self.bin_dir / "initdb", "-D", self.data, "-U", self.USER, "-A", "trust", "--no-sync",
                   "-E", "UTF8", "--locale", "C"])
        options = (f"-c listen_addresses=127.0.0.1 -p {self.port} -k {self.root} -c fsync=off "
                   f"-c synchronous_commit=off -c full_page_writes=off -c max_connections=50")
        self._run([self.bin_dir / "pg_ctl", "-D", self.data, "-l", self.root / "server.log", "-o", options,
                   "-w", "-t", "30", "start"])

    def _run(self, argv) -> None:
        result = subprocess.run([*self._as, *map(str, argv)], capture_output=True, text=True)
        if result.returncode != 0:
            log = self.root / "server.log"
            raise RuntimeError(f"{argv[0]} failed: {result.stdout}{result.stderr}"
                               f"{log.read_text() if log.exists() else ''}")

    def url(self, dbname: str = "postgres") -> str:
        """``postgresql://tactip@127.0.0.1:PORT/dbname``."""
        return f"postgresql://{self.USER}@127.0.0.1:{self.port}/{dbname}"

    def create_database(self, name: str) -> str:
        """Create (anew) database ``name`` and return its URL."""
        import psycopg

        with psycopg.connect(self.url(), autocommit=True) as db:
            db.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
            db.execute(f'CREATE DATABASE "{name}"')
        return self.url(name)

    def stop(self) -> None:
        """Stop the server and delete its folder."""
        try:
            self._run([self.bin_dir / "pg_ctl", "-D", self.data, "-m", "immediate", "-w", "stop"])
        finally:
            shutil.rmtree(self.root, ignore_errors=True)


def artefacts_dir(name: str) -> Path:
    """A folder for a test's artefacts (screenshots, measured figures), kept after the run.

    ``$TACTIP_TEST_ARTEFACTS/name``, by default ``out/test-artefacts/name`` in the repository.
    """
    root = os.environ.get("TACTIP_TEST_ARTEFACTS") or Path(__file__).resolve().parents[2] / "out" / "test-artefacts"
    folder = Path(root) / name
    folder.mkdir(parents=True, exist_ok=True)
    return folder
