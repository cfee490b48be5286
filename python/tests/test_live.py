"""`slipfront.run(..., live=...)`: the live view from Python. A plain-socket
WebSocket client (written here, RFC 6455, no library) subscribes to /global
and decodes what it receives with the schema the server advertises; the
values must be the run's own records."""

import base64
import json
import os
import socket
import struct
import sys
import threading

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

import slipfront


class Client:
    """A minimal Foxglove WebSocket client (subprotocol foxglove.sdk.v1)."""

    def __init__(self, host, port):
        self.sock = socket.create_connection((host, port), timeout=30)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           "Sec-WebSocket-Version: 13\r\n"
                           "Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            head += self.sock.recv(1)
        assert head.startswith(b"HTTP/1.1 101"), head
        assert b"foxglove.sdk.v1" in head.lower(), head

    def _exact(self, n):
        data = b""
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                raise EOFError
            data += chunk
        return data

    def frame(self):
        """(opcode, payload) of the next frame; (None, b"") at the end."""
        try:
            b0, b1 = self._exact(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._exact(8))[0]
            return b0 & 0x0F, self._exact(n)
        except (EOFError, ConnectionError):
            return None, b""

    def send_text(self, text):
        payload = text.encode()
        mask = os.urandom(4)
        masked = bytes(c ^ mask[k % 4] for k, c in enumerate(payload))
        n = len(payload)
        length = bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n)
        self.sock.sendall(bytes([0x81]) + length + mask + masked)


def schema_class(channel):
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


class Announced:
    """Stands in for sys.stderr: notes the live view's address."""

    def __init__(self):
        self.url = None
        self.ready = threading.Event()

    def write(self, text):
        if "live view at " in text:
            self.url = text.split("live view at ")[1].split()[0]
            self.ready.set()
        return len(text)

    def flush(self):
        pass


def test_a_live_run_streams_its_global_series_to_a_websocket_client(monkeypatch):
    announced = Announced()
    monkeypatch.setattr(sys, "stderr", announced)
    received = []

    def viewer():
        assert announced.ready.wait(60)
        host, port = announced.url.removeprefix("ws://").rsplit(":", 1)
        client = Client(host, int(port))
        channels = {}
        while "/global" not in channels:
            op, payload = client.frame()
            message = json.loads(payload) if op == 1 else {}
            if message.get("op") == "advertise":
                channels.update({c["topic"]: c for c in message["channels"]})
        client.send_text(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": 7, "channelId": channels["/global"]["id"]}]}))
        Global = schema_class(channels["/global"])
        while True:
            op, payload = client.frame()
            if op is None or op == 8:
                return
            if op == 2 and payload[0] == 1:
                sub, log_time = struct.unpack("<IQ", payload[1:13])
                assert sub == 7
                received.append((log_time, Global.FromString(payload[13:])))

    thread = threading.Thread(target=viewer)
    thread.start()
    r = slipfront.run("small_stick_slip", backend="cpu", t_end=0.01, progress=False,
                      live="127.0.0.1:0", live_wait=True)
    thread.join(60)
    assert r.summary["live"] == announced.url
    times = np.asarray(r.series["time"])
    assert len(received) == len(times) > 100
    got = np.array([m.drive_ratio for _, m in received])
    assert np.array_equal(got, np.asarray(r.series["drive_ratio"]))
    assert np.array_equal([m.step for _, m in received], np.asarray(r.series["step"]))
    assert [t for t, _ in received] == [int(t * 1e9) for t in times]


def test_live_addresses_are_checked():
    with pytest.raises(ValueError, match="live: `nowhere`"):
        slipfront.run("small_stick_slip", t_end=1e-4, progress=False, live="nowhere")
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    port = taken.getsockname()[1]
    with pytest.raises(OSError, match=f"127.0.0.1:{port}: cannot listen there"):
        slipfront.run("small_stick_slip", t_end=1e-4, progress=False, live=f"127.0.0.1:{port}")
    taken.close()
