#!/usr/bin/python3
"""The web viewer's times and memory: for each .vxl given, `voxlines share` it, serve the folder over HTTP on
this machine, open it in headless Chromium (software WebGL2: SwiftShader) and report, per round, the
milliseconds from navigation to the first picture (drawn at a coarser level of detail for a large file) and to
full detail, and the browser's peak memory: the proportional set size (PSS) of all its processes together,
sampled every 100 ms, against the file's size. PSS, not the resident set: Chromium's processes share the
pages of its binary and the shared memory the page hands the GPU process, which the resident sets of the
processes each count whole (summed, about twice the memory); PSS counts a shared page once, divided among
the processes that map it. The server answers Range requests (as nginx or Apache do; the page then fetches
the first picture's level first), or with --server whole ignores them (as `python3 -m http.server`: the page
fetches the file whole), or with --server first-range answers one range a request.

Also the memory of each kind of Chromium process at the peak (browser, renderer: the page and its
WebAssembly memory, gpu-process: SwiftShader's copies of the textures), the tab's own peak (the largest renderer
process: the page's; the others are Chromium's spare ones) and its memory once the page is done, against the bytes
the page has on the GPU once done (what it draws), the level drawn at rest, by ranges the
bytes fetched, and once the page is done its WebAssembly memory (and malloc's use of it: now and at most) and
its JavaScript heap. --gpu sets the page's GPU memory budget (?gpu=); --rate sends range answers at that many MB
a second, as a network would (by ranges, full detail then arrives span by span: the pictures at rest drawn with
some of its spans in, and when the first was shown).

Each round starts a browser of its own (a cold browser: its GPU process, SwiftShader, starts with the page), or
with --warm all rounds run in one browser, a tab after another: the first round's browser is cold, the later
rounds' warm (as for a recipient who has a browser open, or opens a second link).

Usage: bench/web_bench.py FILE.vxl... [--rounds N] [--warm] [--size WxH] [--server ranges|first-range|whole]
       [--gpu SIZE] [--rate MB_PER_S] [--voxlines PATH]
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'scripts'))
import web_capture  # noqa: E402
import web_server  # noqa: E402

SERVERS = {'ranges': web_server.RangeHandler, 'first-range': web_server.FirstRangeHandler,
           'whole': web_server.QuietHandler}


def process_kind(pid):
    """Chromium's name for what a process does (--type=renderer, gpu-process, ...); 'browser' for the main one."""
    try:
        with open(f'/proc/{pid}/cmdline', 'rb') as f:
            for arg in f.read().replace(b'\0', b' ').split():  # children rewrite their title: spaces
                if arg.startswith(b'--type='):
                    return arg[7:].decode()
    except OSError:
        pass
    return 'browser'


def process_memory_bytes(pid):
    """A process's proportional set size (its private pages, and its share of those it shares), or its resident
    set where the kernel gives no smaps_rollup; None once it has gone."""
    try:
        with open(f'/proc/{pid}/smaps_rollup') as f:
            for line in f:
                if line.startswith('Pss:'):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        with open(f'/proc/{pid}/statm') as f:
            return int(f.read().split()[1]) * os.sysconf('SC_PAGE_SIZE')
    except OSError:
        return None


def tree_memory_bytes(root):
    """The memory of `root` and every process below it (process_memory_bytes): [(kind, bytes)] (process_kind)."""
    children = {}
    for pid in os.listdir('/proc'):
        if not pid.isdigit():
            continue
        try:
            with open(f'/proc/{pid}/stat') as f:
                fields = f.read().rsplit(')', 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(pid))
        except OSError:
            continue
    processes, todo = [], [root]
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        memory = process_memory_bytes(pid)
        if memory is not None:
            processes.append((process_kind(pid), memory))
    return processes


class PeakSampler:
    def __init__(self):
        self.peak, self.tab_peak, self._root, self._stop = 0, 0, None, threading.Event()
        self.tab_done = 0  # the tab's memory once the page is done (sample_done)
        self.at_peak = {}  # {kind: bytes} when the total peaked
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self, process):
        self._root = process.pid
        self._thread.start()

    def _run(self):
        while not self._stop.wait(0.1):
            processes = tree_memory_bytes(self._root)
            by_kind = {}
            for kind, memory in processes:
                by_kind[kind] = by_kind.get(kind, 0) + memory
            self.tab_peak = max([self.tab_peak] + [memory for kind, memory in processes if kind == 'renderer'])
            if sum(by_kind.values()) > self.peak:
                self.peak, self.at_peak = sum(by_kind.values()), by_kind

    def sample_done(self):
        """The tab's memory now: the page is done, its tab still open."""
        self.tab_done = max([0] + [memory for kind, memory in tree_memory_bytes(self._root) if kind == 'renderer'])

    def stop(self):
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('files', nargs='+')
    parser.add_argument('--rounds', type=int, default=2)
    parser.add_argument('--warm', action='store_true', help='all rounds in one browser (the first cold, then warm)')
    parser.add_argument('--size', default='1024x1024')
    parser.add_argument('--server', choices=sorted(SERVERS), default='ranges')
    parser.add_argument('--gpu', help="the page's GPU memory budget (?gpu=, e.g. 256M)")
    parser.add_argument('--rate', type=float, default=0,
                        help='MB a second the server sends range answers and whole data files at (a network; default: at once)')
    parser.add_argument('--voxlines', default=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..',
                                                           'build', 'release', 'converter', 'voxlines'))
    parser.add_argument('--chromium', default=shutil.which('chromium') or 'chromium')
    args = parser.parse_args()
    web_server.RangeHandler.rate = args.rate * 1e6
    with tempfile.TemporaryDirectory(prefix='voxweb-bench-') as work:
        for path in args.files:
            folder = os.path.join(work, os.path.basename(path) + '.share')
            subprocess.run([args.voxlines, 'share', path, folder], check=True, capture_output=True)
            server = web_server.Server(folder, SERVERS[args.server])
            url = f'{server.url}index.html?size={args.size}' + (f'&gpu={args.gpu}' if args.gpu else '')
            size = os.path.getsize(path)
            shared = web_capture.Browser(args.chromium) if args.warm else None
            try:
                for r in range(args.rounds):
                    sampler = PeakSampler()
                    web_server.RangeHandler.reset_counts()
                    t0 = time.monotonic()
                    picture = os.path.join(work, 'picture.png')
                    try:
                        if shared:
                            sampler.start(shared.process)
                            report = shared.capture(url, picture, 900, on_done=sampler.sample_done)
                        else:
                            report = web_capture.capture(url, picture, 900, args.chromium, on_start=sampler.start,
                                                         on_done=sampler.sample_done)
                    finally:
                        sampler.stop()
                    if 'error' in report:
                        print(f'{os.path.basename(path)}: {report["error"]}')
                        return 1
                    browser = 'warm' if shared and r > 0 else 'cold'
                    # A file larger than the page holds is drawn from a level image, whose level 0 is the file's
                    # level_offset: the levels said are the file's.
                    offset = report.get('level_offset') or 0
                    first_level = report['first_level'] + offset
                    full_level = None if report.get('full_level') is None else report['full_level'] + offset
                    print(f'{os.path.basename(path)} ({size / 2**20:.0f} MiB, server: {args.server}) round {r + 1}, {browser} browser: first picture '
                          f'{report["first_picture_ms"] / 1000:.2f} s (level {first_level}), full detail {report["full_detail_ms"] / 1000:.2f} s, '
                          f'browser peak PSS {sampler.peak / 2**20:.0f} MiB = {sampler.peak / size:.2f}x the file '
                          f'(whole run {time.monotonic() - t0:.1f} s)', flush=True)
                    looks = report.get('looks') or []
                    if looks:
                        shown = ', '.join(f'level {look["level"]} at {look["at"] / 1000:.2f} s' for look in looks)
                        print(f'    the package\'s looks before the whole (a level of detail alone, unpacked from the bytes '
                              f'in): {shown}; then the whole, at full detail', flush=True)
                    kinds = ', '.join(f'{k} {v / 2**20:.0f}' for k, v in sorted(sampler.at_peak.items()))
                    fetched = (f'; fetched by ranges {web_server.RangeHandler.bytes_sent / 2**20:.0f} MiB'
                               if args.server != 'whole' else '')
                    budget = f', GPU budget {args.gpu}' if args.gpu else ''
                    page, memory = '', report.get('memory')
                    if memory and memory.get('peak') is not None and report.get('heap_bytes') is not None:
                        page = (f'; once done, the page\'s WebAssembly memory {memory["wasm"] / 2**20:.0f} MiB (malloc: '
                                f'{memory["in_use"] / 2**20:.0f} MiB in use, {memory["peak"] / 2**20:.0f} MiB at most), '
                                + (f'the package\'s unpacker\'s at its end {memory["unpacker"] / 2**20:.0f} MiB, '
                                   if memory.get('unpacker') else '') +
                                f'JavaScript heap {report["heap_bytes"] / 2**20:.0f} MiB')
                    if memory and memory.get('gpu_bytes'):
                        page += (f'; the tab at most {sampler.tab_peak / 2**20:.0f} MiB = '
                                 f'{sampler.tab_peak / memory["gpu_bytes"]:.2f}x the {memory["gpu_bytes"] / 2**20:.0f} MiB '
                                 f'it draws from (on the GPU once done), once done {sampler.tab_done / 2**20:.0f} MiB = '
                                 f'{sampler.tab_done / memory["gpu_bytes"]:.2f}x')
                    image = f' (a level image from level {offset}: the file is larger than the page holds)' if offset else ''
                    print(f'    at the peak, MiB: {kinds}; drawn at rest: level {full_level}{image}{budget}'
                          f'{fetched}{page}', flush=True)
                    spans = report.get('spans_fetched') or []
                    if spans:
                        mixed = report.get('mixed_shown') or []
                        print(f'    full detail fetched in {len(spans)} spans ({sum(s["in_view"] for s in spans)} in view, '
                              f'the nearest first); pictures at rest shown with some of them in: {len(mixed)}' +
                              (f', the first at {mixed[0] / 1000:.2f} s' if mixed else ''), flush=True)
                    steps = ', '.join(f'{name} {ms / 1000:.2f}' for name, ms in report.get('marks', []))
                    print(f'    on the way to the first picture, s from navigation: {steps}', flush=True)
                    tasks = report.get('long_tasks')
                    if tasks is not None:
                        after = [d for start, d in tasks if start >= report['first_picture_ms']]
                        print(f'    the page\'s tasks of 50 ms and more: {len(tasks)}, the longest {max([0] + [d for _, d in tasks]):.0f} ms; '
                              f'after the first picture {len(after)}, the longest {max([0] + after):.0f} ms, '
                              f'{sum(after) / 1000:.1f} s in all', flush=True)
                    calls = sorted(report.get('slow_calls') or [], key=lambda c: -c[2])
                    if calls:
                        print('    the longest calls into the viewer, ms (at s from navigation): ' +
                              ', '.join(f'{name} {ms:.0f} ({start / 1000:.1f})' for name, start, ms in calls[:8]),
                              flush=True)
            finally:
                if shared:
                    shared.close()
                server.close()
    return 0


if __name__ == '__main__':
    sys.exit(main())
