#!/usr/bin/env python3
# A minimal Tracy capture (protocol 82, Tracy 0.14): connect to a running client, take its LZ4 stream for a while,
# and report which of the given zone names appear in it and how often.
import socket, struct, sys, time, lz4.block
names = [n.encode() for n in sys.argv[2:]]
seconds = float(sys.argv[1])
deadline = time.time() + 60
while True:
    try:
        s = socket.create_connection(("127.0.0.1", 8086), timeout=5); break
    except OSError:
        if time.time() > deadline: sys.exit("no Tracy client listening on 8086")
        time.sleep(0.05)
s.sendall(b"TracyPrf" + struct.pack("<I", 82))
def recv(n):
    b = b""
    while len(b) < n:
        c = s.recv(n - len(b))
        if not c: raise EOFError
        b += c
    return b
status = recv(1)[0]
print("handshake status", status)
welcome = recv(8 * 8 + 1 + 1 + 12 + 4 + 64 + 1024)
flags = welcome[64]
print("program", welcome[64 + 2 + 12 + 4:64 + 2 + 12 + 4 + 64].split(b"\0")[0].decode(), "ondemand", flags & 1)
if flags & 1:
    frames, now = struct.unpack("<QQ", recv(16))
    print("on-demand: frames before connecting", frames)
out = bytearray()
end = time.time() + seconds
s.settimeout(2)
try:
    while time.time() < end:
        (size,) = struct.unpack("<I", recv(4))
        data = recv(size)
        dic = bytes(out[-65536:])
        out += lz4.block.decompress(data, uncompressed_size=256 * 1024, dict=dic) if dic else lz4.block.decompress(data, uncompressed_size=256 * 1024)
except (EOFError, socket.timeout, OSError) as e:
    print("stream ended:", type(e).__name__)
print("bytes", len(out))
for n in names:
    print(n.decode(), out.count(n))
