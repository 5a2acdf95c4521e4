#!/usr/bin/env python3
"""Issue 17's table, re-run: each row sends what a careless or hostile user would and says what
the daemon did (status, time, RSS, alive). Starts its own daemon on a free loopback port.

Usage: bench/service-table.py [--scatterd build/scatterd] [--rows 1,2,...]
Prints one line per row; docs/BENCHMARKS.md quotes them ("The service's table").
"""
import argparse, base64, http.client as httplib, json, os, re, signal, socket, struct, subprocess, sys, tempfile, threading, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Daemon:
    def __init__(self, binary, *args):
        self.dir = tempfile.mkdtemp(prefix="scatter-table-")
        self.log = open(os.path.join(self.dir, "serve.log"), "w+")
        self.proc = subprocess.Popen([binary, "serve", "--port", "0", "--scenes-dir", os.path.join(ROOT, "scenes"),
                                      "--cache-dir", os.path.join(self.dir, "cache"), *args],
                                     stdout=self.log, stderr=subprocess.STDOUT)
        for _ in range(300):
            self.log.seek(0)
            m = re.search(r"serving on http://[^:]+:(\d+)/", self.log.read())
            if m:
                self.port = int(m.group(1))
                return
            if self.proc.poll() is not None:
                break
            time.sleep(0.1)
        raise SystemExit("scatterd did not start")

    def alive(self):
        return self.proc.poll() is None

    def rss_mb(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            return int(re.search(r"VmRSS:\s+(\d+)", f.read()).group(1)) / 1024

    def stop(self):
        if self.alive():
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(10)


def http(port, method, path, body=b"", headers=None, timeout=300):
    c = httplib.HTTPConnection("127.0.0.1", port, timeout=timeout)
    t = time.monotonic()
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, data, (time.monotonic() - t) * 1000


class Ws:
    """A minimal WebSocket client (RFC 6455, masked client frames)."""

    def __init__(self, port, path="/api/ws"):
        self.s = socket.create_connection(("127.0.0.1", port))
        key = base64.b64encode(os.urandom(16)).decode()
        self.s.sendall((f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                        f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.s.recv(1)
            if not chunk:
                raise ConnectionError("closed during the upgrade")
            head += chunk
        self.status = int(head.split()[1])
        if self.status != 101:
            raise ConnectionError(f"upgrade refused: {self.status}")

    def send_raw(self, payload, opcode=1):
        mask = os.urandom(4)
        n = len(payload)
        header = bytes([0x80 | opcode])
        header += bytes([0x80 | n]) if n < 126 else (bytes([0xFE]) + struct.pack(">H", n) if n < 65536
                                                      else bytes([0xFF]) + struct.pack(">Q", n))
        self.s.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def send(self, obj):
        self.send_raw(json.dumps(obj).encode())

    def recv(self):
        def exactly(n):
            b = b""
            while len(b) < n:
                chunk = self.s.recv(n - len(b))
                if not chunk:
                    raise ConnectionError("closed")
                b += chunk
            return b
        h = exactly(2)
        n = h[1] & 0x7F
        if n == 126:
            n = struct.unpack(">H", exactly(2))[0]
        elif n == 127:
            n = struct.unpack(">Q", exactly(8))[0]
        return h[0] & 0x0F, exactly(n)

    def next_json(self):
        while True:
            op, data = self.recv()
            if op == 1:
                return json.loads(data)
            if op == 8:
                raise ConnectionError("closed by the server")


def scene(**over):
    s = {"mesh": {"shape": "sphere", "radius": 1.0}, "medium": {"sigma_s": [1, 1, 1], "sigma_a": [0.1, 0.1, 0.1]},
         "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0}],
         "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
         "image": {"width": 64, "height": 64}}
    s.update(over)
    return s


def verdict(d, status, ms=None, extra=""):
    return f"{status}" + (f" in {ms:.0f} ms" if ms is not None else "") + (f", {extra}" if extra else "") + \
        (", daemon alive" if d.alive() else ", DAEMON DEAD")


def row_nesting(d):
    deep = "[" * 100000 + "]" * 100000
    st, body, ms = http(d.port, "POST", "/api/render", ('{"scene": ' + deep + "}").encode())
    return "POST /api/render nesting arrays 100,000 deep", verdict(d, st, ms, json.loads(body)["error"][:60])


def row_off(d):
    out = []
    for text in ["OFF\n3 1 0\n0 0 0\n", "OFF\n4 2 0\n0 0 0\n", "OFF\n100 100 0\n0 0 0\n"]:
        st, body, ms = http(d.port, "POST", "/api/assets?kind=mesh&format=off", text.encode())
        out.append(str(st))
    return "OFF uploads naming vertices that do not exist (3 1 0, 4 2 0, 100 100 0)", verdict(d, "/".join(out))


def row_cost(d):
    lights = [{"type": "point", "position": [3, 3, 3], "intensity": 10}] * 16
    r = []
    for pipeline, settings in [("reference", {"spp": 3}), ("thickness", {"shadow_size": 8192})]:
        before = d.rss_mb()
        st, body, ms = http(d.port, "POST", "/api/render", json.dumps(
            {"scene": scene(voxels=512 if pipeline == "reference" else 64, lights=lights), "pipeline": pipeline,
             "settings": settings}).encode())
        j = json.loads(body)
        label = ("sphere, voxels 512, 16 lights, reference, spp 3" if pipeline == "reference"
                 else "thickness, 16 lights, shadow_size 8192")
        r.append((label, verdict(d, st, ms, f"field {j.get('field')}, RSS {before:.0f} -> {d.rss_mb():.0f} MB")))
    return r


def row_concurrent_health(d):
    body = json.dumps({"scene_name": "sphere", "pipeline": "reference", "format": "json", "settings": {"spp": 64}})
    threads = [threading.Thread(target=http, args=(d.port, "POST", "/api/render", body.encode())) for _ in range(4)]
    for t in threads:
        t.start()
    time.sleep(1)
    ms = sorted(http(d.port, "GET", "/api/health")[2] for _ in range(50))
    for t in threads:
        t.join()
    return "4 concurrent reference renders, then GET /api/health x50", verdict(d, 200, None, f"health p50 {ms[25]:.1f} ms, max {ms[-1]:.1f} ms")


def row_sigterm(binary):
    d = Daemon(binary, "--max-render-s", "100000")
    body = json.dumps({"scene_name": "sphere", "pipeline": "reference", "format": "json", "settings": {"spp": 100000}})
    def client():
        try:
            http(d.port, "POST", "/api/render", body.encode())
        except OSError:  # told 503, or the connection closed at the exit: either is an answer
            pass
    for _ in range(4):
        threading.Thread(target=client, daemon=True).start()
    time.sleep(2)
    t = time.monotonic()
    d.proc.send_signal(signal.SIGTERM)
    d.proc.wait(30)
    return "SIGTERM with renders queued and one running", f"exit {d.proc.returncode} after {time.monotonic() - t:.2f} s"


def row_psf_bake(d):
    st, body, ms = http(d.port, "POST", "/api/bakes", json.dumps({"scene_name": "sphere", "pipeline": "psf"}).encode())
    return "POST /api/bakes with pipeline psf", verdict(d, st, ms)


def row_shipped(d):
    req = json.dumps({"scene_name": "bunny", "pipeline": "surface", "format": "json"}).encode()
    out = []
    for _ in range(2):
        st, body, ms = http(d.port, "POST", "/api/render", req)
        out.append(f"{ms:.0f} ms (scene_load {json.loads(body)['timings_ms'].get('scene_load', 0):.0f} ms)")
    return "POST /api/render of bunny/surface, twice", verdict(d, 200, None, " then ".join(out))


def row_ack_flood(d):
    bad = Ws(d.port)
    bad.send({"type": "hello", "scene_name": "bunny", "pipeline": "surface"})
    honest = Ws(d.port)
    honest.send({"type": "hello", "scene_name": "bunny", "pipeline": "surface"})
    before = d.rss_mb()
    stop = time.monotonic() + 20
    frames = 0
    r = 0
    h = honest.next_json()
    while time.monotonic() < stop:
        for _ in range(50):  # acks for frames it never read, and poses
            r += 1
            bad.send({"type": "camera", "position": [4 * (r % 7) / 7 - 2, 0.5, 4], "revision": r})
            bad.send({"type": "ack", "frame": r})
        honest.send({"type": "camera", "position": [0.1 * (frames % 10), 0.5, 4], "revision": frames + 1})
        honest.send({"type": "ack", "frame": h["frame"]})
        while True:
            h = honest.next_json()
            if h.get("type") == "frame":
                break
        frames += 1
    st, _, hms = http(d.port, "GET", "/api/health")
    return ("a client acking frames it never read (20 s) beside an honest session",
            verdict(d, 200, None, f"RSS {before:.0f} -> {d.rss_mb():.0f} MB, honest session {frames / 20:.1f} fps, "
                                  f"health {hms:.1f} ms"))


def row_mtllib(d):
    cube = ("v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
            "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n")
    fifo = os.path.join(d.dir, "fifo.mtl")
    os.mkfifo(fifo)
    out = []
    for mtl in ["../../../../../../../../etc/passwd", fifo]:
        st, body, ms = http(d.port, "POST", "/api/assets?kind=mesh&format=obj", f"mtllib {mtl}\n{cube}".encode(), timeout=30)
        out.append(f"{st} in {ms:.0f} ms")
    return "OBJ uploads with mtllib ../../etc/passwd, and naming a FIFO", verdict(d, " / ".join(out))


def row_bake_with_sessions(d):
    sessions = []
    for _ in range(4):
        w = Ws(d.port)
        w.send({"type": "hello", "scene_name": "sphere", "pipeline": "surface"})
        sessions.append(w)
    st, body, _ = http(d.port, "POST", "/api/bakes", json.dumps(
        {"scene_name": "layers", "pipeline": "single", "settings": {"samples": 50000}}).encode())
    job = json.loads(body)["id"]
    time.sleep(3)
    polls = sorted(http(d.port, "GET", f"/api/bakes/{job}")[2] for _ in range(20))
    _, _, health = http(d.port, "GET", "/api/health")
    st, body, dms = http(d.port, "DELETE", f"/api/bakes/{job}")
    return ("a 50k-sample bake with 4 live sessions: status polls, health, a DELETE 3 s in",
            verdict(d, st, dms, f"polls p50 {polls[10]:.1f} ms max {polls[-1]:.1f} ms, health {health:.1f} ms"))


def row_silent(binary):
    d = Daemon(binary, "--session-idle-s", "5")
    silent = [Ws(d.port) for _ in range(16)]
    t = time.monotonic()
    while True:
        try:
            Ws(d.port)
            break
        except ConnectionError:
            time.sleep(0.2)
    took = time.monotonic() - t
    d.stop()
    return "16 silent WebSocket connections (--session-idle-s 5)", f"a 17th admitted after {took:.1f} s"


def row_token(binary):
    p = subprocess.run([binary, "serve", "--port", "0", "--token", ""], capture_output=True, text=True, timeout=30)
    d = Daemon(binary, "--token", "a+b/c=d")
    st, _, _ = http(d.port, "GET", "/api/health?token=a%2Bb%2Fc%3Dd")
    d.stop()
    return [("--token \"\"", f"exit {p.returncode}: {p.stderr.strip()[:70]}"),
            ("a token with URL-special characters, percent-encoded in ?token=", f"{st}")]


def row_bad_requests(d):
    st1, b1, _ = http(d.port, "POST", "/api/render", json.dumps({"scene": scene(mesh={"file": "nope.obj"})}).encode())
    s = socket.create_connection(("127.0.0.1", d.port))
    s.sendall(b"GET /api/health HTTP/1.1\r\nHost: x\r\nX-Pad: " + b"x" * 20000 + b"\r\n\r\n")
    head = s.recv(100).split(b"\r\n")[0].decode()
    s.close()
    return "a scene naming a missing mesh; 20 kB of headers", verdict(
        d, f"{st1} ({json.loads(b1)['error'][:50]}); {head}")


def row_connections(d):
    before = d.rss_mb()
    idle = [socket.create_connection(("127.0.0.1", d.port)) for _ in range(500)]
    half = []
    for _ in range(500):
        s = socket.create_connection(("127.0.0.1", d.port))
        s.sendall(b"POST /api/render HTTP/1.1\r\nHost: x\r\nContent-Length: 1000\r\n\r\n{")
        half.append(s)
    w = Ws(d.port)
    w.send_raw(b"\xff\xfe\xfd")  # invalid UTF-8 in a text frame
    g = Ws(d.port)
    try:
        g.send_raw(os.urandom(10 << 20), opcode=2)
    except OSError:
        pass
    time.sleep(1)
    st, _, ms = http(d.port, "GET", "/api/health")
    after = d.rss_mb()
    for s in idle + half:
        s.close()
    return "500 idle + 500 half-open connections, invalid UTF-8, a 10 MB garbage frame", verdict(
        d, st, ms, f"RSS {before:.0f} -> {after:.0f} MB")


def main():
    a = argparse.ArgumentParser()
    a.add_argument("--scatterd", default=os.path.join(ROOT, "build/scatterd"))
    args = a.parse_args()
    d = Daemon(args.scatterd)
    rows = []
    for f in [row_nesting, row_off, row_cost, row_concurrent_health, row_psf_bake, row_shipped, row_ack_flood,
              row_mtllib, row_bake_with_sessions, row_bad_requests, row_connections]:
        try:
            r = f(d)
        except Exception as e:  # the row's own failure, reported as such
            r = (f.__name__, f"FAILED: {e!r}" + ("" if d.alive() else ", DAEMON DEAD"))
        rows += r if isinstance(r, list) else [r]
        print(f"| {rows[-1][0]} | {rows[-1][1]} |" if not isinstance(r, list) else
              "\n".join(f"| {x[0]} | {x[1]} |" for x in r), flush=True)
        if not d.alive():
            d = Daemon(args.scatterd)
    d.stop()
    for f in [row_sigterm, row_silent, row_token]:
        r = f(args.scatterd)
        print("\n".join(f"| {x[0]} | {x[1]} |" for x in (r if isinstance(r, list) else [r])), flush=True)


if __name__ == "__main__":
    main()
