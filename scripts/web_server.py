#!/usr/bin/python3
"""Static web servers for the web viewer's test and benchmark, on a free port of this machine, in a thread:

* `QuietHandler`: Python's own, which ignores Range (every answer is the whole file, status 200), as
  `python3 -m http.server` serves a shared folder;
* `RangeHandler`: answers `Range: bytes=...` with 206, one range as it is and several as multipart/byteranges,
  as nginx or Apache do;
* `FirstRangeHandler`: answers only the first of several ranges (a server or proxy that does not do multipart);
* `WholeForSeveralHandler`: answers several ranges with the whole file (status 200), as servers do past a limit.

Usage as a program: scripts/web_server.py FOLDER [--port N] [--no-range] serves FOLDER until interrupted.
"""
import argparse
import functools
import http.server
import os
import re
import threading
import time
import uuid


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


class RangeHandler(QuietHandler):
    multipart = True
    # What it answered since the last reset: 206 with one range, and 206 with several (multipart/byteranges); and
    # the bytes of the file those answers held.
    answers = {'one range': 0, 'multipart': 0}
    bytes_sent = 0
    # Bytes a second the range answers and whole data files are sent at, as over a network slower than this machine
    # (0: at once).
    rate = 0

    @classmethod
    def reset_counts(cls):
        RangeHandler.answers = {'one range': 0, 'multipart': 0}
        RangeHandler.bytes_sent = 0

    def do_GET(self):
        spec = self.headers.get('Range')
        path = self.translate_path(self.path.split('?')[0])
        if not spec or not os.path.isfile(path):
            if os.path.isfile(path) and path.endswith(('.vxl', '.vxlz')):
                RangeHandler.bytes_sent += os.path.getsize(path)  # the whole file
                if RangeHandler.rate:
                    return self.send_whole(path)
            return super().do_GET()
        size = os.path.getsize(path)
        ranges = self.parse_ranges(spec, size)
        if ranges is None:
            return super().do_GET()  # a Range header this server does not understand: the whole file
        if not ranges:
            self.send_response(416)
            self.send_header('Content-Range', f'bytes */{size}')
            self.send_header('Content-Length', '0')
            self.end_headers()
            return
        if not self.multipart:
            ranges = ranges[:1]
        RangeHandler.bytes_sent += sum(end + 1 - begin for begin, end in ranges)
        with open(path, 'rb') as f:
            def read(begin, end):
                f.seek(begin)
                return f.read(end - begin + 1)
            if len(ranges) == 1:
                begin, end = ranges[0]
                body = read(begin, end)
                self.send_response(206)
                self.send_header('Content-Type', 'application/octet-stream')
                self.send_header('Content-Range', f'bytes {begin}-{end}/{size}')
                RangeHandler.answers['one range'] += 1
            else:
                RangeHandler.answers['multipart'] += 1
                boundary = uuid.uuid4().hex
                pieces = []
                for begin, end in ranges:
                    pieces.append(f'\r\n--{boundary}\r\nContent-Type: application/octet-stream\r\n'
                                  f'Content-Range: bytes {begin}-{end}/{size}\r\n\r\n'.encode('latin1'))
                    pieces.append(read(begin, end))
                pieces.append(f'\r\n--{boundary}--\r\n'.encode('latin1'))
                body = b''.join(pieces)
                self.send_response(206)
                self.send_header('Content-Type', f'multipart/byteranges; boundary={boundary}')
        self.send_header('Content-Length', str(len(body)))
        self.send_header('Accept-Ranges', 'bytes')
        self.end_headers()
        self.send_body(body)

    def send_whole(self, path):
        """The whole file (200) at the rate."""
        with open(path, 'rb') as f:
            body = f.read()
        self.send_response(200)
        self.send_header('Content-Type', 'application/octet-stream')
        self.send_header('Content-Length', str(len(body)))
        self.end_headers()
        self.send_body(body)

    def send_body(self, body):
        if not RangeHandler.rate:
            return self.wfile.write(body)
        start, piece = time.monotonic(), 1 << 16
        for at in range(0, len(body), piece):
            self.wfile.write(body[at:at + piece])
            ahead = start + (at + piece) / RangeHandler.rate - time.monotonic()
            if ahead > 0:
                time.sleep(ahead)

    @staticmethod
    def parse_ranges(spec, size):
        """[(first, last), ...] inclusive and within the file; [] when none is; None when not `bytes=`."""
        m = re.fullmatch(r'\s*bytes=(.+)', spec)
        if not m:
            return None
        ranges = []
        for part in m.group(1).split(','):
            a, _, b = part.strip().partition('-')
            if a == '' and b.isdigit():  # the last b bytes
                first, last = max(0, size - int(b)), size - 1
            elif a.isdigit() and (b == '' or b.isdigit()):
                first, last = int(a), min(size - 1, int(b) if b else size - 1)
            else:
                return None
            if first <= last and first < size:
                ranges.append((first, last))
        return ranges


class FirstRangeHandler(RangeHandler):
    multipart = False


class WholeForSeveralHandler(RangeHandler):
    """Answers one range with 206 and several with the whole file (200), as servers do past a limit on ranges."""

    def do_GET(self):
        spec = self.headers.get('Range') or ''
        if ',' in spec:
            return QuietHandler.do_GET(self)
        return super().do_GET()


class Server:
    """A static web server for one folder on a free port (or `port`), in a thread."""

    def __init__(self, folder, handler_class=RangeHandler, port=0):
        handler = functools.partial(handler_class, directory=folder)
        self.httpd = http.server.ThreadingHTTPServer(('127.0.0.1', port), handler)
        self.url = f'http://127.0.0.1:{self.httpd.server_address[1]}/'
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def close(self):
        self.httpd.shutdown()


if __name__ == '__main__':
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('folder')
    parser.add_argument('--port', type=int, default=8000)
    parser.add_argument('--no-range', action='store_true')
    args = parser.parse_args()
    server = Server(args.folder, QuietHandler if args.no_range else RangeHandler, args.port)
    print(f'serving {args.folder} at {server.url} (Ctrl-C stops)')
    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        server.close()
