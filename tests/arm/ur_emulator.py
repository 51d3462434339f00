"""A Universal Robots controller emulator, to test the UR backend through the real ur-rtde client.

It runs in its own process (the ur-rtde constructors hold the GIL, so an in-process server would starve)
and listens on 127.0.0.1 on the ports ur-rtde uses:

- 29999 dashboard server: line protocol (PolyscopeVersion, is in remote control, robotmode, safetystatus,
  programState, stop, unlock protective stop, ...);
- 30004 RTDE, protocol version 2: request protocol version ('V'), controller version ('v'), setup outputs
  ('O', frequency + names -> recipe id + types, NOT_FOUND for unknown names), setup inputs ('I', recipe
  ids numbered per connection from 1), start ('S'), pause ('P'), data packages ('U') both ways;
- 30003 script port: receives the control script ur-rtde uploads; a complete ``def ...: ... end``
  program starts running (runtime state PLAYING).

While the uploaded script runs, the emulator plays its register handshake: the command is in
input_int_register_0; output_int_register_0 is 1 when ready for a command and 2 when done with it; a
command of 0 clears. moveL (3) takes the pose in input double registers 0-5 (m, rotation vector in rad),
speed in 6 (m/s), acceleration in 7 (m/s^2) and async in input_int_register_1; stopL (33); set watchdog
(35, minimum frequency in double register 0: the program stops when inputs stop arriving); stop script
(255); set TCP (29). Other commands are acknowledged. Asynchronous progress is in output_int_register_2
(bit 15 running, bits 24-30 operation id, bits 16-23 change count). Motion is simplified: straight lines
at constant speed, ``time_scale`` times faster than real time; orientation jumps at the end of a move.

The test process drives it with `UrEmulator` (a context manager): fault injection and the command log go
through a pipe.
"""

from __future__ import annotations

import fcntl
import multiprocessing
import os
import re
import socket
import struct
import tempfile
import threading
import time

from tests.arm.ur_controller import FORMATS, PLAYING, Controller, Options, value_count, input_type, output_type

HOST = "127.0.0.1"
DASHBOARD_PORT, RTDE_PORT, SCRIPT_PORT = 29999, 30004, 30003


class RtdeSession(threading.Thread):
    """One RTDE client connection: the control-package dialogue, then data packages both ways."""

    def __init__(self, sock: socket.socket, controller: Controller):
        super().__init__(daemon=True)
        self.sock, self.controller = sock, controller
        self.send_lock = threading.Lock()
        self.inputs: dict[int, list[str]] = {}
        self.outputs: list[str] = []
        self.frequency = 125.0
        self.started = threading.Event()
        self.closed = False

    def send(self, kind: bytes, payload: bytes = b"") -> None:
        """Send one message: uint16 size, uint8 type, payload."""
        with self.send_lock:
            self.sock.sendall(struct.pack(">HB", 3 + len(payload), kind[0]) + payload)

    def run(self) -> None:
        """Serve the connection until the client closes it."""
        threading.Thread(target=self._stream, daemon=True).start()
        try:
            while True:
                header = self._read(3)
                size, kind = struct.unpack(">HB", header)
                self._handle(chr(kind), self._read(size - 3))
        except (ConnectionError, OSError):
            pass
        finally:
            self.closed = True
            self.started.set()
            self.sock.close()

    def _read(self, count: int) -> bytes:
        data = b""
        while len(data) < count:
            chunk = self.sock.recv(count - len(data))
            if not chunk:
                raise ConnectionError("client closed")
            data += chunk
        return data

    def _handle(self, kind: str, payload: bytes) -> None:
        if kind == "V":
            self.send(b"V", struct.pack(">B", struct.unpack(">H", payload)[0] == 2))
        elif kind == "v":
            major, minor, bugfix, build = (int(p) for p in self.controller.options.polyscope.split("."))
            self.send(b"v", struct.pack(">IIII", major, minor, bugfix, build))
        elif kind == "O":
            self.frequency = struct.unpack(">d", payload[:8])[0]
            self.outputs = [n for n in payload[8:].decode().split(",") if n]
            self.send(b"O", struct.pack(">B", 1) + ",".join(map(output_type, self.outputs)).encode())
        elif kind == "I":
            names = [n for n in payload.decode().split(",") if n]
            recipe = len(self.inputs) + 1
            self.inputs[recipe] = names
            self.send(b"I", struct.pack(">B", recipe) + ",".join(map(input_type, names)).encode())
        elif kind == "S":
            self.send(b"S", b"\x01")
            self.started.set()
        elif kind == "P":
            self.started.clear()
            self.send(b"P", b"\x01")
        elif kind == "U":
            names = self.inputs.get(payload[0], [])
            fmt = ">" + "".join(FORMATS[input_type(n)] for n in names)
            flat = struct.unpack(fmt, payload[1:1 + struct.calcsize(fmt)])
            values, i = {}, 0
            for name in names:
                width = value_count(FORMATS[input_type(name)])
                values[name] = flat[i] if width == 1 else flat[i:i + width]
                i += width
            with self.controller.lock:
                self.controller.apply_inputs(values)

    def _stream(self) -> None:
        while not self.closed:
            if not self.started.wait(0.05) or self.closed:
                continue
            with self.controller.lock:
                self.controller.step()
                values = [self.controller.value(n) for n in self.outputs]
            fmt = ">B" + "".join(FORMATS[output_type(n)] for n in self.outputs)
            flat = []
            for v in values:
                flat.extend(v if isinstance(v, tuple) else [v])
            try:
                self.send(b"U", struct.pack(fmt, 1, *flat))
            except OSError:
                return
            time.sleep(1.0 / self.frequency)


def _serve_dashboard(sock: socket.socket, controller: Controller) -> None:
    sock.sendall(b"Connected: Universal Robots Dashboard Server\n")
    reader = sock.makefile("r", newline="\n")
    try:
        for line in reader:
            command = line.strip()
            with controller.lock:
                reply = _dashboard_reply(command, controller)
            sock.sendall(reply.encode() + b"\n")
            if command == "quit":
                break
    except OSError:
        pass
    finally:
        sock.close()


def _dashboard_reply(command: str, c: Controller) -> str:
    running = c.runtime == PLAYING
    replies = {
        "PolyscopeVersion": f"URSoftware {c.options.polyscope} (Mar 22 2021)",
        "is in remote control": "true" if c.options.remote_control else "false",
        "robotmode": f"Robotmode: {c.robot_mode}",
        "safetystatus": f"Safetystatus: {c.safety}",
        "safetymode": f"Safetymode: {c.safety}",
        "programState": f"{'PLAYING' if running else 'STOPPED'} <unnamed>",
        "running": f"Program running: {str(running).lower()}",
        "get serial number": "20195500001",
        "get robot model": "UR5",
        "close safety popup": "closing safety popup",
        "quit": "Disconnected",
    }
    if command == "stop":
        c.stop_program()
        return "Stopped"
    if command == "unlock protective stop":
        return "Protective stop releasing" if c.unlock_protective_stop() else "Cannot unlock protective stop"
    return replies.get(command, f"could not understand: '{command}'")


def _serve_script(sock: socket.socket, controller: Controller) -> None:
    text = ""
    try:
        while chunk := sock.recv(65536):
            text += chunk.decode(errors="replace")
            if re.search(r"^def \w+\(\):.*^end\s*$", text, flags=re.S | re.M):
                with controller.lock:
                    controller.log.append({"cmd": "script", "bytes": len(text), "t": 0.0})
                    if controller.options.run_uploaded_script:
                        controller.start_program()
                text = ""
    except OSError:
        pass
    finally:
        sock.close()


def _listen(port: int) -> socket.socket:
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((HOST, port))
    server.listen(8)
    return server


def _accept_forever(server: socket.socket, handler, controller: Controller) -> None:
    while True:
        try:
            sock, _ = server.accept()
        except OSError:
            return
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        if handler is RtdeSession:
            RtdeSession(sock, controller).start()
        else:
            threading.Thread(target=handler, args=(sock, controller), daemon=True).start()


def run_emulator(options: Options, pipe) -> None:
    """Process entry point: listen on the three ports, then answer the test's requests on ``pipe``."""
    try:
        servers = [_listen(port) for port in (DASHBOARD_PORT, RTDE_PORT, SCRIPT_PORT)]
    except OSError as exc:
        pipe.send(("error", f"cannot listen on the UR ports {DASHBOARD_PORT}/{RTDE_PORT}/{SCRIPT_PORT}: {exc}"))
        return
    controller = Controller(options)
    for server, handler in zip(servers, (_serve_dashboard, RtdeSession, _serve_script)):
        threading.Thread(target=_accept_forever, args=(server, handler, controller), daemon=True).start()
    pipe.send(("ready", None))
    while True:
        request, argument = pipe.recv()
        with controller.lock:
            if request == "close":
                break
            if request == "log":
                pipe.send(list(controller.log))
            elif request == "protective_stop":
                controller.protective_stop() if argument == "now" else setattr(controller, "stop_during_next_move", True)
                pipe.send(None)
            elif request == "stop_program":
                controller.stop_program()
                pipe.send(None)
            elif request == "set":
                for key, value in argument.items():
                    for target in (controller, controller.options):
                        if hasattr(target, key):
                            setattr(target, key, value)
                pipe.send(None)
            elif request == "reset":
                controller.__init__(Options(**argument))
                pipe.send(None)
            elif request == "state":
                pipe.send({"tcp": controller.tcp.tolist(), "runtime": controller.runtime,
                           "safety": controller.safety, "robot_mode": controller.robot_mode})
    for server in servers:
        server.close()
    pipe.send(None)


#: A lock file that the emulators of one machine take turns on: the UR ports are fixed (ur-rtde cannot
#: be pointed at others), so two test processes (pytest-xdist workers) wait for each other instead of
#: one of them skipping its tests.
PORTS_LOCK = os.path.join(tempfile.gettempdir(), "tactip-ur-emulator-ports.lock")


class UrEmulator:
    """The emulator process, seen from a test: ``with UrEmulator() as emu: ...``.

    Holds `PORTS_LOCK` (waiting for another test process's emulator to close) while it runs. Raises
    `PortsBusy` when the UR ports cannot be bound even so: something else on this machine has them
    (the tests skip with that reason).
    """

    def __init__(self, **options):
        self.options = Options(**options)
        context = multiprocessing.get_context("spawn")
        self._pipe, child = context.Pipe()
        self._process = context.Process(target=run_emulator, args=(self.options, child), daemon=True)

    def __enter__(self) -> UrEmulator:
        self._lock = open(PORTS_LOCK, "a")
        fcntl.flock(self._lock, fcntl.LOCK_EX)  # another test process's emulator: wait for it to close
        try:
            self._process.start()
            if not self._pipe.poll(30):
                self._process.kill()
                raise RuntimeError("the UR emulator did not start")
            status, message = self._pipe.recv()
            if status == "error":
                self._process.join(5)
                raise PortsBusy(message)
        except BaseException:
            self._release()
            raise
        return self

    def _release(self) -> None:
        fcntl.flock(self._lock, fcntl.LOCK_UN)
        self._lock.close()

    def __exit__(self, *exc_info) -> None:
        if self._process.is_alive():
            try:
                self._pipe.send(("close", None))
                self._pipe.poll(5) and self._pipe.recv()
            except (OSError, EOFError):
                pass
        self._process.join(5)
        if self._process.is_alive():
            self._process.kill()
            self._process.join(5)
        self._release()

    def _ask(self, request: str, argument=None):
        self._pipe.send((request, argument))
        return self._pipe.recv()

    def log(self) -> list[dict]:
        """Every command the emulated control script received, in order."""
        return self._ask("log")

    def moves(self) -> list[dict]:
        """The moveL commands received (pose in m / rad, speed m/s, acceleration m/s^2)."""
        return [entry for entry in self.log() if entry["cmd"] == 3]

    def protective_stop(self, *, during_next_move: bool = False) -> None:
        """Trigger a protective stop now, or half-way through the next move."""
        self._ask("protective_stop", "next" if during_next_move else "now")

    def stop_program(self) -> None:
        """Stop the control program (as if stopped from the pendant)."""
        self._ask("stop_program")

    def set(self, **values) -> None:
        """Change options or controller attributes (e.g. ``robot_mode="POWER_OFF"``)."""
        self._ask("set", values)

    def reset(self, **options) -> None:
        """Back to a fresh controller (program stopped, safety normal, empty log) with these options."""
        self._ask("reset", options)

    def state(self) -> dict:
        """TCP pose (m, rad), runtime state, safety and robot mode."""
        return self._ask("state")


class PortsBusy(RuntimeError):
    """The UR ports are taken on this machine."""
