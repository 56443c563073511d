"""Reaching a Dask scheduler (issue 36): every connection has one deadline and every refusal is
one line, exit 2, well under 30 s.

Hostile peers run in threads on 127.0.0.1 with ephemeral ports: one that accepts and never
answers, an HTTP server, one that sends other bytes, one that closes at once, and a bound port
where nothing listens. Each is given to the real command in a subprocess, timed from outside.
A real scheduler without workers (an in-process LocalCluster) checks the wait for workers.
"""

from __future__ import annotations

import contextlib
import http.server
import logging
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from seahaze.batch import BatchRefusedError
from seahaze.batch.dask_connect import (
    SchedulerAddress,
    connect_dask,
    parse_scheduler_address,
    probe_scheduler,
)
from seahaze.cli import main

distributed = pytest.importorskip("distributed")

SCENE = """\
name: tiny
camera: {height_m: 12, pitch_deg: -2, resolution: [48, 27]}
sun: {elevation_deg: 30, azimuth_deg: 140}
sea: {quality: low, seed: 99}
haze: {levels: [1000]}
render: {spp: 1, airlight_spp: 16, seed: 3}
"""

# What a real scheduler of distributed 2026.8 writes on accepting a connection: the byte count,
# one frame of 42 bytes, and that frame (a msgpack map).
HANDSHAKE = (
    b":\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00*\x00\x00\x00\x00\x00\x00\x00"
    b"\x83\xabcompression\xc0\xa6python\x93\x03\x0b\x07\xafpickle-protocol\x05"
)

LIMIT_S = 30.0


@pytest.fixture
def scene(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(SCENE, encoding="utf-8")
    return path


def _render(scene: Path, out: Path, scheduler: str, *extra: str) -> tuple[int, str, float]:
    """Exit code, stderr and wall-clock seconds of the real command against ``scheduler``."""
    command = [sys.executable, "-m", "seahaze.cli", "render", str(scene), "--out", str(out)]
    command += ["--executor", "dask", "--scheduler", scheduler]
    command += ["--res", "16x9", "--spp", "1", "--quiet", *extra]
    start = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    return done.returncode, done.stderr, time.monotonic() - start


def _assert_one_line_refusal(code: int, err: str, seconds: float, *says: str) -> None:
    lines = err.splitlines()
    assert code == 2, err
    assert seconds < LIMIT_S, f"{seconds:.1f} s"
    assert "Traceback" not in err
    assert len(lines) == 1 and lines[0].startswith("seahaze: error: "), err
    for text in says:
        assert text in lines[0], err


@contextlib.contextmanager
def _peer(serve: Callable[[socket.socket, threading.Event], None]) -> Iterator[str]:
    """A TCP server on 127.0.0.1 whose every connection is given to ``serve``; its address."""
    stop = threading.Event()
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(0.1)

    def accept() -> None:
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except TimeoutError:
                continue
            threading.Thread(target=_serve_and_close, args=(serve, conn, stop), daemon=True).start()

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    finally:
        stop.set()
        thread.join()
        listener.close()


def _serve_and_close(
    serve: Callable[[socket.socket, threading.Event], None],
    conn: socket.socket,
    stop: threading.Event,
) -> None:
    with conn, contextlib.suppress(OSError):
        serve(conn, stop)


def _silent(conn: socket.socket, stop: threading.Event) -> None:
    # Reads (so a request cannot fill the buffers) and never writes: a hung service.
    conn.settimeout(0.1)
    while not stop.is_set():
        with contextlib.suppress(TimeoutError):
            if not conn.recv(4096):
                return


def _garbage(conn: socket.socket, stop: threading.Event) -> None:
    conn.sendall(b"\xde\xad\xbe\xef" * 16)  # read as a length: 17 EB
    _silent(conn, stop)


def _banner(conn: socket.socket, stop: threading.Event) -> None:
    conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
    _silent(conn, stop)


def _hang_up(conn: socket.socket, stop: threading.Event) -> None:
    pass


def _late_handshake(conn: socket.socket, stop: threading.Event) -> None:
    # A scheduler whose event loop was busy: its handshake comes only after the HTTP question.
    conn.settimeout(5)
    conn.recv(4096)
    conn.sendall(HANDSHAKE)
    _silent(conn, stop)


class _Head(http.server.BaseHTTPRequestHandler):
    def do_HEAD(self) -> None:
        self.send_response(200)
        self.end_headers()

    def log_message(self, format: str, *args: object) -> None:
        pass


@contextlib.contextmanager
def _http_server() -> Iterator[str]:
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Head)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@contextlib.contextmanager
def _nothing_listens() -> Iterator[str]:
    # A bound socket that does not listen holds the port, so nothing else can take it, and
    # every connection to it is refused.
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        yield f"tcp://127.0.0.1:{sock.getsockname()[1]}"


@pytest.mark.parametrize(
    ("peer", "says"),
    [
        (lambda: _peer(_silent), "accepted the connection but never answered"),
        (_http_server, "an HTTP server answered"),
        (lambda: _peer(_garbage), "answered with bytes that are not the Dask protocol"),
        (_nothing_listens, "connection refused"),
    ],
    ids=["silent", "http", "garbage", "refused"],
)
def test_a_peer_that_is_not_a_scheduler_is_one_line_in_time(scene, tmp_path, peer, says):
    with peer() as address:
        code, err, seconds = _render(scene, tmp_path / "out", address)
    print(f"{says}: {seconds:.1f} s")
    _assert_one_line_refusal(code, err, seconds, repr(address), says)
    assert not (tmp_path / "out").exists()  # refused before the folder is made


@pytest.mark.parametrize(
    ("address", "says"),
    [
        ("notanaddress", "no port"),
        ("127.0.0.1:65536", "within 1..65535"),
        ("http://127.0.0.1:8787", "unknown scheme 'http://'"),
    ],
)
def test_a_malformed_address_is_refused_at_once(scene, tmp_path, address, says):
    code, err, seconds = _render(scene, tmp_path / "out", address)
    _assert_one_line_refusal(code, err, seconds, repr(address), says, "tcp://HOST:PORT")
    assert seconds < 10


def test_a_host_name_that_does_not_resolve_is_one_line(scene, tmp_path):
    code, err, seconds = _render(scene, tmp_path / "out", "tcp://no-such-host.invalid:8786")
    _assert_one_line_refusal(code, err, seconds, "no-such-host.invalid", "does not resolve")


def test_a_scheduler_without_workers_is_waited_for_then_refused(scene, tmp_path):
    with distributed.LocalCluster(
        n_workers=0,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
        silence_logs=logging.ERROR,
    ) as cluster:
        address = cluster.scheduler_address
        code, err, seconds = _render(scene, tmp_path / "out", address, "--dask-wait", "2")
    lines = err.splitlines()
    assert code == 2 and seconds < LIMIT_S and "Traceback" not in err, err
    assert len(lines) == 2, err
    assert lines[0].startswith("seahaze: warning: ") and "waiting up to 2 s" in lines[0]
    assert repr(address) in lines[0] and "no workers" in lines[0]
    assert lines[1].startswith("seahaze: error: no Dask worker joined") and "within 2 s" in lines[1]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("tcp://10.0.0.5:8786", SchedulerAddress("tcp://10.0.0.5:8786", "tcp", "10.0.0.5", 8786)),
        ("head:8786", SchedulerAddress("head:8786", "tcp", "head", 8786)),
        (
            "TLS://head.cluster:1",
            SchedulerAddress("TLS://head.cluster:1", "tls", "head.cluster", 1),
        ),
        ("ws://[::1]:65535", SchedulerAddress("ws://[::1]:65535", "ws", "[::1]", 65535)),
        (
            "inproc://10.0.0.5/123/1",
            SchedulerAddress("inproc://10.0.0.5/123/1", "inproc", "10.0.0.5/123/1", None),
        ),
    ],
)
def test_accepted_addresses(text, expected):
    assert parse_scheduler_address(text) == expected


@pytest.mark.parametrize(
    "text",
    [
        "",
        " ",
        "notanaddress",
        "tcp://head",
        "head:",
        ":8786",
        "head:0",
        "head:-1",
        "head:8786x",
        "head:８７８６",
        "::1:8786",
        "tcp://head:8786/status",
        "://head:8786",
        "udp://head:8786",
        "tcp://he ad:8786",
        "tcp://head:8786\n",
        "inproc://",
    ],
)
def test_malformed_addresses(text):
    with pytest.raises(BatchRefusedError) as refused:
        parse_scheduler_address(text)
    message = str(refused.value)
    assert "\n" not in message and repr(text) in message and "tcp://HOST:PORT" in message


@pytest.mark.parametrize(
    ("serve", "says"),
    [
        (_banner, "not the Dask protocol (b'SSH-2.0-OpenSSH_'...)"),
        (_hang_up, "closed it without a word"),
    ],
)
def test_other_peers_are_named_by_the_probe(serve, says):
    with _peer(serve) as address, pytest.raises(BatchRefusedError) as refused:
        connect_dask(address, timeout_s=5)
    assert says in str(refused.value) and repr(address) in str(refused.value)


def _handshake_then_silence(conn: socket.socket, stop: threading.Event) -> None:
    conn.sendall(HANDSHAKE)
    _silent(conn, stop)


def _handshake_then_garbage(conn: socket.socket, stop: threading.Event) -> None:
    conn.sendall(HANDSHAKE)
    conn.settimeout(5)
    conn.recv(4096)
    conn.sendall(b"\xff" * 64)
    _silent(conn, stop)


@pytest.mark.parametrize(
    ("serve", "says"),
    [
        (_handshake_then_silence, "no complete answer within"),
        (_handshake_then_garbage, "ValueError"),
    ],
    ids=["silence", "garbage"],
)
def test_a_peer_that_passes_the_probe_but_not_the_client_is_one_line(serve, says):
    # Past the probe, distributed.Client's own failures become the refusal, in the deadline.
    with _peer(serve) as address:
        start = time.monotonic()
        with pytest.raises(BatchRefusedError) as refused:
            connect_dask(address, timeout_s=2)
    message = str(refused.value)
    assert time.monotonic() - start < 5
    assert "\n" not in message and repr(address) in message and says in message


def test_a_late_handshake_is_still_a_scheduler():
    with _peer(_late_handshake) as address:
        start = time.monotonic()
        probe_scheduler(
            parse_scheduler_address(address), start + 5, first_wait_s=0.2, reply_wait_s=2
        )
    assert time.monotonic() - start < 2


def test_the_probe_keeps_its_deadline():
    with _peer(_silent) as address:
        start = time.monotonic()
        with pytest.raises(BatchRefusedError, match="never answered"):
            probe_scheduler(parse_scheduler_address(address), start + 1)
    assert time.monotonic() - start < 2


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--executor", "dask", "--scheduler", "head:8786", "--dask-wait", "0"], "--dask-wait 0"),
        (["--executor", "dask", "--scheduler", "head:8786", "--dask-wait", "nan"], "nan"),
        (["--dask-wait", "5"], "--dask-wait needs --executor dask"),
    ],
)
def test_bad_dask_wait_is_bad_input(scene, tmp_path, capsys, args, says):
    assert main(["render", str(scene), "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.splitlines()) == 1
