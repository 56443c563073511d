"""Reaching a Dask scheduler under one deadline, with a one-line reason when it cannot be done.

``distributed.Client`` alone turns every mistake in ``--scheduler`` into a long wait and a
traceback: a malformed address ends in a ``TimeoutError`` after half a minute, a peer that
accepts and never answers (or an HTTP server, such as the dashboard on :8787) keeps it waiting
for many minutes, and a peer that sends other bytes makes it allocate whatever length they
spell (exabytes). So the address is parsed first, then a plain socket probes it: a Dask server
writes its handshake as soon as it accepts a connection (``Comm.on_connection`` in
``distributed/comm/core.py`` writes before it reads), so its first bytes tell a Dask scheduler
from anything else before the Client is made. Only then does the Client connect, in what is
left of the same deadline, and a scheduler without workers is waited for a bounded time.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import re
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from .errors import BatchRefusedError

DASK_CONNECT_TIMEOUT_S = 15
"""How long to try reaching a Dask scheduler before giving up: resolving its host, the probe
and the Client's own handshake together."""

DASK_WAIT_S = 60.0
"""How long to wait for a first worker when the scheduler has none (``--dask-wait``)."""

FIRST_BYTES_WAIT_S = 3.0
"""How long the probe waits for a peer's first bytes. A Dask scheduler sends its handshake at
once; a busy one's event loop may lag, and a late handshake is still recognised after the
HTTP question (below), so this only decides when that question is asked."""

HTTP_REPLY_WAIT_S = 3.0
"""How long the probe waits for an answer to ``HEAD / HTTP/1.0`` from a peer that said
nothing."""

TCP_SCHEMES = ("tcp",)
"""Schemes whose first bytes are Dask's TCP framing, which the probe can check."""

STREAM_SCHEMES = ("tls", "ws", "wss")
"""Schemes over TCP whose first bytes the probe cannot read (TLS or a websocket come first):
only resolving the host and connecting is checked; the Client's timeout covers the rest."""

OTHER_SCHEMES = ("ucx", "inproc")
"""Schemes without a TCP socket to probe: left to the Client's timeout."""

ACCEPTED_FORMS = (
    "use tcp://HOST:PORT or HOST:PORT, e.g. tcp://10.0.0.5:8786 "
    "(also tls://, ws://, wss://, ucx:// HOST:PORT, or inproc://)"
)

_HOST = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?|\[[0-9A-Fa-f:.]+(?:%[\w.-]+)?\]")
_SCHEME = re.compile(r"([A-Za-z][A-Za-z0-9+.-]*)://(.*)", re.DOTALL)

# Dask's TCP framing (distributed/comm/tcp.py, _add_frames_header and pack_frames_prelude in
# protocol/utils.py): a uint64 count of the bytes that follow in one piece, then the prelude
# (a uint64 number of frames and a uint64 length per frame), then the frames; a msgpack map is
# the first frame of a handshake. All native byte order, i.e. little-endian on every platform
# distributed runs on. A handshake is one frame of some 40 bytes, so generous bounds still
# reject almost any other bytes within the first 8.
_U64 = struct.Struct("<Q")
_MAX_FRAMES = 64
_MAX_HANDSHAKE_BYTES = 1 << 20
_MSGPACK_MAP_FIRST = frozenset(range(0x80, 0x90)) | {0xDE, 0xDF}


@dataclass(frozen=True)
class SchedulerAddress:
    """A parsed ``--scheduler`` address: the text as given, its scheme, host and port."""

    text: str
    scheme: str
    host: str
    port: int | None

    @property
    def url(self) -> str:
        """The address for ``distributed.Client``, with its scheme (lower case) spelled out."""
        if self.port is None:
            return f"{self.scheme}://{self.host}"
        return f"{self.scheme}://{self.host}:{self.port}"

    @property
    def name(self) -> str:
        """The host as the resolver wants it (IPv6 without its brackets)."""
        return self.host[1:-1] if self.host.startswith("[") else self.host


def _malformed(text: str, why: str) -> BatchRefusedError:
    return BatchRefusedError(
        f"Dask scheduler address {text!r} is malformed: {why}; {ACCEPTED_FORMS}"
    )


def parse_scheduler_address(text: str) -> SchedulerAddress:
    """``text`` as a scheduler address: ``tcp://HOST:PORT``, ``HOST:PORT`` (TCP), the same with
    ``tls://``, ``ws://``, ``wss://`` or ``ucx://``, or ``inproc://...``.

    Raises :class:`BatchRefusedError` naming the address and the accepted forms otherwise.
    """
    if not text.strip():
        raise _malformed(text, "empty")
    if any(c.isspace() or not c.isprintable() for c in text):
        raise _malformed(text, "it holds spaces or control characters")
    match = _SCHEME.fullmatch(text)
    if match:
        scheme, rest = match.group(1).lower(), match.group(2)
    elif "://" in text:
        raise _malformed(text, "no scheme before '://'")
    else:
        scheme, rest = "tcp", text
    if scheme not in TCP_SCHEMES + STREAM_SCHEMES + OTHER_SCHEMES:
        raise _malformed(text, f"unknown scheme '{scheme}://'")
    if scheme == "inproc":
        if not rest:
            raise _malformed(text, "nothing after 'inproc://'")
        return SchedulerAddress(text, scheme, rest, None)
    if "/" in rest:
        raise _malformed(text, "a path after the port")
    host, colon, port_text = rest.rpartition(":")
    if not colon:
        raise _malformed(text, "no port")
    if not host:
        raise _malformed(text, "no host")
    if not _HOST.fullmatch(host):
        why = " (an IPv6 address needs brackets, e.g. [::1]:8786)" if ":" in host else ""
        raise _malformed(text, f"{host!r} is not a host name or address{why}")
    if not port_text.isascii() or not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise _malformed(text, f"port {port_text!r} is not a number within 1..65535")
    return SchedulerAddress(text, scheme, host, int(port_text))


def _unreachable(address: SchedulerAddress, why: str) -> BatchRefusedError:
    return BatchRefusedError(f"cannot reach the Dask scheduler at {address.text!r}: {why}")


def _not_dask(address: SchedulerAddress, why: str) -> BatchRefusedError:
    return BatchRefusedError(f"no Dask scheduler at {address.text!r}: {why}")


def _left(deadline: float) -> float:
    return max(0.0, deadline - time.monotonic())


def _resolve(address: SchedulerAddress, deadline: float) -> list[Any]:
    """The socket addresses of ``address``'s host, within the deadline (the resolver has no
    timeout of its own, so it runs in a thread that is abandoned when the deadline passes)."""
    found: list[Any] = []
    failed: list[OSError] = []

    def lookup() -> None:
        try:
            found.extend(socket.getaddrinfo(address.name, address.port, type=socket.SOCK_STREAM))
        except OSError as err:
            failed.append(err)
        except UnicodeError as err:  # a host name the IDNA codec refuses
            failed.append(OSError(str(err)))

    started = time.monotonic()
    thread = threading.Thread(target=lookup, daemon=True, name="seahaze-dask-resolve")
    thread.start()
    thread.join(_left(deadline))
    if thread.is_alive():
        waited = time.monotonic() - started
        raise _unreachable(
            address, f"the host name {address.name!r} did not resolve within {waited:.0f} s"
        )
    if failed or not found:
        why = failed[0].strerror or str(failed[0]) if failed else "no addresses"
        raise _unreachable(address, f"the host name {address.name!r} does not resolve ({why})")
    return found


def _connect(address: SchedulerAddress, deadline: float) -> socket.socket:
    """A TCP connection to the first of the host's addresses that accepts one."""
    error: OSError | None = None
    started = time.monotonic()
    for family, kind, proto, _name, sockaddr in _resolve(address, deadline):
        if _left(deadline) <= 0:
            break
        sock = socket.socket(family, kind, proto)
        try:
            sock.settimeout(_left(deadline))
            sock.connect(sockaddr)
        except OSError as err:
            sock.close()
            error = err
            continue
        return sock
    where = f"port {address.port} of {address.name}"
    if isinstance(error, ConnectionRefusedError):
        raise _unreachable(address, f"connection refused (nothing listens on {where})")
    if isinstance(error, TimeoutError) or error is None:
        raise _unreachable(
            address,
            f"no answer to the connection within {time.monotonic() - started:.0f} s "
            "(a host that is down, or a firewall dropping the packets)",
        )
    if error.errno in (errno.ENETUNREACH, errno.EHOSTUNREACH):
        raise _unreachable(address, f"host unreachable ({error.strerror})")
    raise _unreachable(address, f"cannot connect to {where} ({error.strerror or error})")


def _classify(data: bytes) -> Literal["dask", "http", "other"] | None:
    """What a peer's first bytes are; ``None`` while too few have come to tell."""
    if data[:5] == b"HTTP/"[: len(data)]:
        return "http" if len(data) >= 5 else None
    # Lengths are sanity-checked, never trusted: a handshake is small, so the high bytes of the
    # first uint64 are zero, and so are those of the frame count.
    if any(data[3:8]):
        return "other"
    if len(data) < 8:
        return None
    (total,) = _U64.unpack_from(data)
    if not 3 * _U64.size <= total <= _MAX_HANDSHAKE_BYTES or any(data[9:16]):
        return "other"
    if len(data) < 16:
        return None
    (frames,) = _U64.unpack_from(data, 8)
    prelude = _U64.size * (1 + frames)
    if not 1 <= frames <= _MAX_FRAMES or prelude >= total:
        return "other"
    if len(data) < 8 + prelude + 1:
        return None
    lengths = struct.unpack_from(f"<{frames}Q", data, 16)
    # The count covers the prelude and a leading run of whole frames.
    covered = {sum(lengths[:n]) for n in range(1, frames + 1)}
    if total - prelude not in covered or data[8 + prelude] not in _MSGPACK_MAP_FIRST:
        return "other"
    return "dask"


def _receive(sock: socket.socket, data: bytearray, until: float) -> str | None:
    """Read into ``data`` until its kind is known, the peer closes, or ``until`` passes;
    returns the kind, ``"closed"`` or ``None`` (no verdict in time)."""
    while True:
        kind = _classify(bytes(data)) if data else None
        if kind is not None:
            return kind
        wait = until - time.monotonic()
        if wait <= 0:
            return None
        sock.settimeout(wait)
        try:
            chunk = sock.recv(4096)
        except TimeoutError:
            return None
        except OSError:  # reset by the peer: as good as closed
            return "closed"
        if not chunk:
            return "closed"
        data += chunk


def _sample(data: bytes) -> str:
    return repr(bytes(data[:16])) + ("..." if len(data) > 16 else "")


def probe_scheduler(
    address: SchedulerAddress,
    deadline: float,
    *,
    first_wait_s: float = FIRST_BYTES_WAIT_S,
    reply_wait_s: float = HTTP_REPLY_WAIT_S,
) -> None:
    """Check, before ``distributed.Client`` is made, that ``address`` can be a Dask scheduler,
    all by the ``time.monotonic()`` ``deadline``.

    For TCP: the host resolves, the port accepts a connection, and the peer's first bytes are
    Dask's handshake. A peer that says nothing for ``first_wait_s`` is asked
    ``HEAD / HTTP/1.0``, and its answer within ``reply_wait_s`` tells an HTTP server (a
    dashboard port) from a peer that never answers. For tls://, ws:// and wss:// only resolving
    and connecting are checked; ucx:// and inproc:// are not probed. Raises
    :class:`BatchRefusedError` with one line naming the address and the cause.
    """
    if address.scheme in OTHER_SCHEMES:
        return
    sock = _connect(address, deadline)
    try:
        if address.scheme not in TCP_SCHEMES:
            return
        data = bytearray()
        first_wait = min(deadline, time.monotonic() + first_wait_s)
        kind = _receive(sock, data, first_wait)
        if kind is None and not data:
            # Silence: a Dask scheduler would have spoken by now. HTTP servers wait for a
            # request, and one line of it is enough to make them say what they are.
            try:
                sock.sendall(b"HEAD / HTTP/1.0\r\n\r\n")
            except OSError:
                kind = "closed"
            else:
                kind = _receive(sock, data, min(deadline, time.monotonic() + reply_wait_s))
    finally:
        sock.close()
    if kind == "dask":
        return
    if kind == "http":
        raise _not_dask(
            address,
            "an HTTP server answered (a Dask dashboard? it is usually on port 8787, "
            "the scheduler on 8786)",
        )
    if data:  # other bytes, or too few to be a handshake before a close or the wait's end
        raise _not_dask(
            address, f"it answered with bytes that are not the Dask protocol ({_sample(data)})"
        )
    if kind == "closed":
        raise _not_dask(address, "it accepted the connection and closed it without a word")
    raise _not_dask(
        address,
        "it accepted the connection but never answered (a Dask scheduler answers at once)",
    )


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _wait_for_a_worker(
    client: Any, address: SchedulerAddress, wait_s: float, note: Callable[[str], None]
) -> None:
    """Return once the scheduler has a worker; give up after ``wait_s`` seconds."""
    if client.nthreads():
        return
    note(
        f"the Dask scheduler at {address.text!r} has no workers; seahaze is waiting up to "
        f"{wait_s:g} s for one (--dask-wait)"
    )
    try:
        client.wait_for_workers(n_workers=1, timeout=wait_s)
    except TimeoutError:
        raise BatchRefusedError(
            f"no Dask worker joined the scheduler at {address.text!r} within {wait_s:g} s; "
            f"start workers (dask worker {address.text}) or wait longer with --dask-wait"
        ) from None


def _stderr_note(message: str) -> None:
    print(f"seahaze: warning: {message}", file=sys.stderr, flush=True)


def connect_dask(
    scheduler: str,
    *,
    wait_s: float = DASK_WAIT_S,
    note: Callable[[str], None] | None = None,
    timeout_s: float | None = None,
) -> Any:
    """A ``distributed.Client`` of the scheduler at ``scheduler`` that has at least one worker.

    The address is parsed and probed (:func:`probe_scheduler`), then the Client connects, all
    within ``timeout_s`` seconds (default :data:`DASK_CONNECT_TIMEOUT_S`). A scheduler without
    workers is reported through ``note`` (default: a warning line on stderr) and waited for up
    to ``wait_s`` seconds.
    Raises :class:`BatchRefusedError` with one line when dask.distributed is missing, the
    address is malformed, nothing Dask answers there in time, or no worker joins.
    """
    address = parse_scheduler_address(scheduler)
    try:
        import distributed
    except ImportError:
        raise BatchRefusedError(
            "--executor dask needs dask.distributed: pip install 'dask[distributed]'"
        ) from None
    deadline = time.monotonic() + (DASK_CONNECT_TIMEOUT_S if timeout_s is None else timeout_s)
    probe_scheduler(address, deadline)
    # The Client retries until its timeout; give it what the probe left, but at least a second
    # for its own handshake.
    timeout = max(1.0, _left(deadline))
    try:
        client = _start_client(distributed.Client, address.url, timeout)
    except (Exception, asyncio.CancelledError) as err:  # never KeyboardInterrupt
        why = _one_line(err)
        if isinstance(err, TimeoutError):  # often without a message of its own
            why = f"no complete answer within {timeout:.0f} s ({why})"
        raise BatchRefusedError(
            f"cannot connect to the Dask scheduler at {scheduler!r}: {why}"
        ) from None
    try:
        _wait_for_a_worker(client, address, wait_s, note or _stderr_note)
    except BaseException as err:
        _close_quietly(client)
        if isinstance(err, BatchRefusedError | KeyboardInterrupt | SystemExit):
            raise
        raise BatchRefusedError(
            f"lost the Dask scheduler at {scheduler!r} while asking for its workers: "
            f"{_one_line(err)}"
        ) from None
    return client


def _start_client(client_class: type, url: str, timeout: float) -> Any:
    """``client_class(url)`` connected within ``timeout`` seconds; a failed one is closed."""
    made: list[Any] = []

    class Tracked(client_class):  # type: ignore[misc, valid-type]
        # Client.__init__ connects itself, and a failed connection leaves a half-made client
        # that nobody holds; its __del__ then closes it at exit, where that can hang for twice
        # the timeout and print a traceback. Holding it lets a failure close it now.
        def start(self, **kwargs: Any) -> None:
            made.append(self)
            super().start(**kwargs)

    try:
        return Tracked(url, timeout=f"{timeout:.3f}s", set_as_default=False)
    except BaseException:
        for client in made:
            _close_quietly(client)
        raise


def _close_quietly(client: Any) -> None:
    # Closing a client that cannot reach its scheduler may fail; the refusal says why already.
    with contextlib.suppress(Exception):
        client.close(timeout=2)
    # Marked closed even when closing failed, so that its __del__ does not try again at exit.
    with contextlib.suppress(Exception):
        client.status = "closed"
