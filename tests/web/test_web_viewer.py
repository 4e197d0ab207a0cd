#!/usr/bin/python3
"""The web viewer draws what voxview draws: a folder made by `voxlines share`, served over HTTP and opened in
headless Chromium (WebGL2 on SwiftShader), against `voxview --render` of the same file with the same camera
(llvmpipe). Two rasterisers draw a line's pixels a little differently, so the pictures are compared by PSNR
over R, G, B (at least MIN_PSNR dB), not byte for byte. Cases: a synthetic set of 20,000 streamlines, packed
and float32, in the axis and unsorted modes; a .vxlz shared as it is (fetched whole and unpacked by the page in a worker,
with the converter's own code built for WebAssembly, its coarse levels looked at first), and the 50k set's over a slow
network (the page asks for a finer level as its bytes come; its .vxl comes back from the worker in two pieces); with the real fixtures (when
--real-data holds them), MRtrix's test tracks coloured by their AFD values; the packed file sent gzip-compressed
(the length the server declares is then not the body's); the packed file dropped on a page opened without one. The
files are served by a server that answers Range
requests (the page then fetches the first picture's level first, many ranges a request), one that answers the
first range only, one that answers several with the whole file, and one that ignores Range (the page then fetches
the file whole). Damaged files, which the page
must refuse with a message naming them (and a file replaced on the server while the page fetches it): one cut short
(the reader's structure checks), two whose structure holds but whose orders or vertices were overwritten (the draw
checks that voxview runs, which the page runs too), and a package with a byte changed (its checksums).

Usage: tests/web/test_web_viewer.py --voxlines PATH --voxview PATH --web-viewer DIR [--real-data DIR]
Exit 0 when every case holds, 1 otherwise, 77 when there is no Chromium to run it in.
"""
import argparse
import gzip
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy
from PIL import Image

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts'))
from web_server import FirstRangeHandler, QuietHandler, RangeHandler, Server, WholeForSeveralHandler  # noqa: E402

MIN_PSNR = 35.0
SLOW_BYTES_PER_S = 0.5e6  # a slow network, for a package's looks at its levels before the whole


class SlowHandler(RangeHandler):
    """Sends the data files at SLOW_BYTES_PER_S (RangeHandler.rate, set while it serves)."""
SIZE = '512x512'
CAPTURE = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts', 'web_capture.py')


def run(*command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: exit {result.returncode}: {result.stdout}{result.stderr}")
    return result.stdout


def psnr_rgb(a_path, b_path):
    a = numpy.asarray(Image.open(a_path).convert('RGB'), dtype=numpy.float64)
    b = numpy.asarray(Image.open(b_path).convert('RGB'), dtype=numpy.float64)
    if a.shape != b.shape:
        raise RuntimeError(f'{a_path} is {a.shape}, {b_path} is {b.shape}')
    mse = ((a - b) ** 2).mean()
    return math.inf if mse == 0 else 10 * math.log10(255 ** 2 / mse)


class GzipHandler(QuietHandler):
    """Sends .vxl files gzip-compressed (Content-Encoding: gzip): the Content-Length the page sees is then the
    compressed size, smaller than the bytes it receives."""

    def do_GET(self):
        if not self.path.split('?')[0].endswith('.vxl'):
            return super().do_GET()
        with open(self.translate_path(self.path.split('?')[0]), 'rb') as f:
            body = gzip.compress(f.read(), compresslevel=1)
        self.send_response(200)
        self.send_header('Content-Type', 'application/octet-stream')
        self.send_header('Content-Encoding', 'gzip')
        self.send_header('Content-Length', str(len(body)))
        self.end_headers()
        self.wfile.write(body)


class ChangingHandler(RangeHandler):
    """Serves changed.vxl as packed.vxl to the first request and as float32.vxl (another size) to the next: a file
    replaced on the server while the page fetches it by ranges."""
    requests = 0

    def translate_path(self, path):
        if not path.split('?')[0].endswith('changed.vxl'):
            return super().translate_path(path)
        ChangingHandler.requests += 1
        return super().translate_path('/packed.vxl' if ChangingHandler.requests == 1 else '/float32.vxl')


def capture(url, out, drop=None):
    """The page's first picture in `out`; returns capture's report (with 'error' when the page refused). `drop`: a
    file (relative to `url`) dropped on the page once it has loaded."""
    result = subprocess.run([sys.executable, CAPTURE, url, out, '--timeout', '120'] + (['--drop', drop] if drop else []),
                            capture_output=True, text=True)
    if result.returncode == 2:
        raise RuntimeError(f'the browser failed: {result.stdout}{result.stderr}')
    return json.loads(result.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--voxlines', required=True)
    parser.add_argument('--voxview', required=True)
    parser.add_argument('--web-viewer', required=True)
    parser.add_argument('--real-data', default='')
    options = parser.parse_args()
    if shutil.which('chromium') is None:
        print('test_web_viewer: SKIPPED: no chromium on this machine (Debian: chromium)')
        return 77

    failures = []
    with tempfile.TemporaryDirectory(prefix='voxweb-test-') as work:
        def path(name):
            return os.path.join(work, name)

        run(options.voxlines, 'synth', path('s20k.tck'), '--streamlines', '20000')
        run(options.voxlines, 'convert', path('s20k.tck'), path('packed.vxl'))
        run(options.voxlines, 'convert', path('s20k.tck'), path('float32.vxl'), '--positions', 'float32')
        run(options.voxlines, 'pack', path('packed.vxl'), path('packed.vxlz'))
        # 50,000 streamlines: a first picture at level 2, so that level 1 is fetched and drawn between it and full
        # detail.
        run(options.voxlines, 'synth', path('s50k.tck'), '--streamlines', '50000')
        run(options.voxlines, 'convert', path('s50k.tck'), path('s50k.vxl'))
        run(options.voxlines, 'pack', path('s50k.vxl'), path('s50k.vxlz'))
        with open(path('packed.vxl'), 'rb') as f:
            whole = f.read()
        with open(path('damaged.vxl'), 'wb') as f:
            f.write(whole[:len(whole) // 2])
        # 4 KiB of 0xFF inside ORDB and inside VERT: orders out of range, vertices with reserved bits set.
        sections = {s['id']: s for s in json.loads(run(options.voxlines, 'info', path('packed.vxl'), '--json'))['sections']}
        for name, section in (('ordb-damaged.vxl', 'ORDB'), ('vert-damaged.vxl', 'VERT')):
            damaged = bytearray(whole)
            at = sections[section]['offset'] + 1000
            damaged[at:at + 4096] = b'\xff' * 4096
            with open(path(name), 'wb') as f:
                f.write(damaged)
        with open(path('packed.vxlz'), 'rb') as f:
            package = bytearray(f.read())
        package[len(package) // 2] ^= 0x40  # inside the positions
        with open(path('damaged.vxlz'), 'wb') as f:
            f.write(package)

        # Each case: the file shared, the page's settings (voxview's options of the same names), the server, and
        # what the page may hold: None, or a GPU memory budget (gpu=SIZE, voxview's --gpu-memory). 16M holds level 1
        # of the 50k set, not full
        # detail: the page then draws level 1 at rest, as voxview does (at a low opacity: a coarse level's few lines,
        # their opacity compensated, make the two rasterisers' differences count more than a dense picture's), and
        # fetches only what level 1 reads, unless a setting reads the whole file (unsorted: then it fetches the rest).
        # Or the page's memory (memory=SIZE): a file larger than it is drawn from a level image of its coarser
        # levels (6M holds the 50k set's level 1 and the coarser ones, not its 33.9 MB), as voxview --level draws
        # that level, fetching only what the image holds.
        cases = [('packed.vxl', 'mode=axis', RangeHandler, None), ('packed.vxl', 'mode=unsorted', QuietHandler, None),
                 ('float32.vxl', 'mode=axis', RangeHandler, None),
                 ('float32.vxl', 'mode=unsorted', FirstRangeHandler, None),
                 ('packed.vxlz', 'mode=axis', WholeForSeveralHandler, None),
                 ('s50k.vxl', 'mode=axis', RangeHandler, None),
                 ('s50k.vxl', 'mode=axis&opacity=0.02', RangeHandler, 'gpu=16M'),
                 ('s50k.vxl', 'mode=unsorted&opacity=0.02', RangeHandler, 'gpu=16M'),
                 ('s50k.vxl', 'mode=axis&opacity=0.02', RangeHandler, 'memory=6M'),
                 ('s50k.vxlz', 'mode=axis', SlowHandler, None)]
        tracks, afd = (os.path.join(options.real_data, f) for f in ('test_data__tracks.tck', 'test_data__afd.tsf'))
        if os.path.isfile(tracks) and os.path.isfile(afd):
            run(options.voxlines, 'convert', tracks, path('afd.vxl'), '--tsf', afd)
            cases.append(('afd.vxl', 'color=scalar&colormap=hot', RangeHandler, None))
        else:
            print(f'the AFD case is skipped: {tracks} is absent (the real fixtures live beside the project)')
        for source in sorted({c[0] for c in cases} | {'damaged.vxl'}):
            folder = path('share-' + source.replace('.', '-'))
            result = subprocess.run([options.voxlines, 'share', path(source), folder, '--web-viewer',
                                     options.web_viewer], capture_output=True, text=True)
            if source == 'damaged.vxl':
                # share opens what it shares: a damaged file is refused before it reaches a browser.
                if result.returncode != 3 or 'damaged.vxl' not in result.stderr or os.path.exists(folder):
                    failures.append(f'share of a damaged file: exit {result.returncode}, {result.stderr.strip()}')
                continue
            if result.returncode != 0:
                failures.append(f'share {source}: exit {result.returncode}: {result.stderr.strip()}')

        # Served compressed: the declared length is not the body's.
        cases.append(('packed.vxl', 'mode=axis', GzipHandler, None))
        served_by = {RangeHandler: 'ranges', FirstRangeHandler: 'first range only', QuietHandler: 'no ranges',
                     SlowHandler: f'ranges, {SLOW_BYTES_PER_S / 1e6:g} MB/s',
                     GzipHandler: 'gzip, no ranges', WholeForSeveralHandler: 'one range, or the whole file for several'}
        for source, settings, handler, holds in cases:
            budget = holds[len('gpu='):] if holds and holds.startswith('gpu=') else None
            memory = holds[len('memory='):] if holds and holds.startswith('memory=') else None
            folder = path('share-' + source.replace('.', '-'))
            shared = json.load(open(os.path.join(folder, 'share.json')))['file']
            server = Server(folder, handler)
            RangeHandler.reset_counts()
            RangeHandler.rate = SLOW_BYTES_PER_S if handler is SlowHandler else 0
            try:
                web = path(f'web-{source}-{settings}.png')
                query = f'size={SIZE}' + (f'&{holds}' if holds else '')
                report = capture(f'{server.url}index.html?{query}#{settings}', web)
            finally:
                server.close()
            if 'error' in report:
                failures.append(f'{source} {settings}: the page failed: {report["error"]}')
                continue
            size = os.path.getsize(os.path.join(folder, shared))
            if source.endswith('.vxlz') and shared != source:
                failures.append(f'{source}: shared as {shared}, not as the package itself')
            # A package is unpacked in a worker (unpack_worker.js), off the page's thread, which marks its answer. A
            # package of a file with levels ships its coarsest levels first: the first picture is a level of detail
            # alone (the 20k set's level 1, under 250,000 points), unpacked from the package's first bytes while the
            # rest arrives; the picture compared below is the whole package's.
            marks = [name for name, _ in report['marks']]
            if source.endswith('.vxlz') and 'unpacked' not in marks and 'look unpacked' not in marks:
                failures.append(f'{source}: not unpacked in a worker (marks: {report["marks"]})')
            # The unpacker hands its .vxl over in pieces of 32 MiB, which the page copies end to end: the 50k set's
            # (33.9 MB) in two, so that the picture compared below is drawn from bytes put together from pieces.
            if source.endswith('.vxlz'):
                pieces = (report.get('memory') or {}).get('unpacked_pieces')
                expected = -(-os.path.getsize(path(source[:-1])) // (32 << 20))  # the .vxl it was packed from
                if pieces != expected or (source == 's50k.vxlz' and expected < 2):
                    failures.append(f'{source}: the unpacked .vxl came in {pieces} pieces of 32 MiB, not {expected}'
                                    ' (the 50k set\'s must take two or more)')
            # Over a slow network the page asks for the finer levels as their bytes come, the whole still far off:
            # the 50k set's package looks at level 2 (its level 1 has more than 250,000 points), then level 1.
            looks = [look['level'] for look in report['looks']]
            if source.endswith('.vxlz') and looks != ([2, 1] if source == 's50k.vxlz' else [1]):
                failures.append(f'{source}: the levels looked at before the whole package were {looks}')
            # Under the budget, level 1 and what opens the file: under a quarter of it (an eighth of the points and
            # orders, the voxel tables); the whole file only for a setting that reads it.
            whole = 'unsorted' in settings
            fetched_as_it_should = RangeHandler.bytes_sent >= size if whole else RangeHandler.bytes_sent <= size // 4
            if holds and not fetched_as_it_should:
                failures.append(f'{source} {settings}, {holds}: {RangeHandler.bytes_sent} of its {size} '
                                'bytes fetched (under a quarter of it, the whole file only for a setting that reads it)')
            # The line under the picture counts the file's points (not its vertices, which add the connecting ones).
            if not report['image']:
                points = json.loads(run(options.voxlines, 'info', path(source), '--json'))['points']
                said = re.sub(r'[\s,.\u00a0\u202f]', '', report.get('info_text') or '')
                if report.get('points') != points or f'{points}points' not in said:
                    failures.append(f'{source}: the page says {report.get("info_text")!r} (info.points '
                                    f'{report.get("points")}), the file has {points} points')
            wanted_mode = dict(kv.split('=') for kv in settings.split('&')).get('mode')
            if wanted_mode and report.get('mode') != wanted_mode:
                failures.append(f'{source} {settings}: drawn in {report.get("mode")}, not {wanted_mode}')
            levels = (report['first_level'], report['levels_shown'], report['full_level'])
            # A level image's levels are its own: its level 0 is the file's level_offset.
            if memory and (not report['image'] or report['level_offset'] != 1 or levels != (1, [], 0)):
                failures.append(f'{source}, memory {memory}: a level image of level {report["level_offset"]} '
                                f'(not 1), its levels {levels} (not a first picture at its level 1, then its level 0)')
            elif source == 's50k.vxl' and not memory and levels != ((2, [], 1) if budget else (2, [1], 0)):
                failures.append(f's50k.vxl, GPU budget {budget}: first picture at level {levels[0]}, then levels '
                                f'{levels[1]} drawn before level {levels[2]} at rest')
            # Full detail fetched span by span, those the view needs first, each group the nearest first.
            spans = report['spans_fetched']
            if handler is RangeHandler and not holds and report['first_level'] > report['full_level'] == 0:
                view = [s['distance'] for s in spans if s['in_view']]
                rest = [s['distance'] for s in spans if not s['in_view']]
                if (len(spans) < 2 or [s['in_view'] for s in spans] != [True] * len(view) + [False] * len(rest) or
                        view != sorted(view) or rest != sorted(rest)):
                    failures.append(f'{source} {settings}: full detail not fetched span by span, the view\'s nearest '
                                    f'first: {spans}')
            # How the page fetched: many ranges a request where the server answers so, one a request where it
            # answers only the first.
            answers = dict(RangeHandler.answers)
            if handler is RangeHandler and answers['multipart'] == 0:
                failures.append(f'{source} {settings}: no multipart/byteranges request by ranges: {answers}')
            if handler is FirstRangeHandler and (answers['multipart'] != 0 or answers['one range'] < 3):
                failures.append(f'{source} {settings}: not fetched one range a request: {answers}')
            native = path(f'voxview-{source}-{settings}.png')
            flags = [x for kv in settings.split('&') for x in ('--' + kv.split('=')[0], kv.split('=')[1])]
            flags += ['--level', '1'] if memory else ['--gpu-memory', budget] if budget else []
            run(options.voxview, os.path.join(folder, shared), '--render', native, '--size', SIZE, *flags)
            value = psnr_rgb(web, native)
            served = f' ({served_by[handler]}' + (f', {holds})' if holds else ')')
            print(f'{source}{served} {settings}: PSNR {value:.2f} dB against voxview, first picture after '
                  f'{report["first_picture_ms"]:.0f} ms, full detail after {report["full_detail_ms"]:.0f} ms; '
                  f'range answers {answers}, {RangeHandler.bytes_sent} of {size} bytes; full detail in '
                  f'{len(report["spans_fetched"])} spans {[round(s["distance"]) for s in report["spans_fetched"]]} '
                  f'(in view {sum(s["in_view"] for s in report["spans_fetched"])}), {len(report["mixed_shown"])} '
                  'pictures with some of them')
            if value < MIN_PSNR:
                keep = os.path.join(tempfile.gettempdir(), 'voxweb-test-failed')
                os.makedirs(keep, exist_ok=True)
                shutil.copy(web, keep)
                shutil.copy(native, keep)
                failures.append(f'{source} {settings}: PSNR {value:.2f} dB < {MIN_PSNR} (pictures in {keep})')

        RangeHandler.rate = 0
        # A file dropped on the page (read from the dropped File, not fetched): a page opened without a file (no
        # share.json), as a recipient's who drops one on it.
        dropped = path('dropped')
        shutil.copytree(path('share-packed-vxl'), dropped)
        os.remove(os.path.join(dropped, 'share.json'))
        server = Server(dropped, QuietHandler)
        try:
            report = capture(f'{server.url}index.html?size={SIZE}#mode=axis', path('web-dropped.png'), drop='packed.vxl')
        finally:
            server.close()
        if 'error' in report:
            failures.append(f'packed.vxl dropped on the page: {report["error"]}')
        else:
            run(options.voxview, path('packed.vxl'), '--render', path('voxview-dropped.png'), '--size', SIZE, '--mode',
                'axis')
            value = psnr_rgb(path('web-dropped.png'), path('voxview-dropped.png'))
            print(f'packed.vxl dropped on the page: PSNR {value:.2f} dB against voxview, first picture after '
                  f'{report["first_picture_ms"]:.0f} ms')
            if value < MIN_PSNR:
                failures.append(f'packed.vxl dropped on the page: PSNR {value:.2f} dB < {MIN_PSNR}')

        # A dropped file larger than the page holds (11M: the 20k set's level 0 without its streamline tables, not its
        # 12.9 MB) is read by parts, as a server's ranges, and drawn from a level image of level 0: as voxview draws
        # the file.
        server = Server(dropped, QuietHandler)
        try:
            report = capture(f'{server.url}index.html?size={SIZE}&memory=11M#mode=axis', path('web-dropped-image.png'),
                             drop='packed.vxl')
        finally:
            server.close()
        if 'error' in report:
            failures.append(f'packed.vxl dropped on the page, memory 11M: {report["error"]}')
        elif not report['image'] or report['level_offset'] != 0:
            failures.append(f'packed.vxl dropped on the page, memory 11M: not read by parts into a level image '
                            f'(image {report["image"]}, level {report["level_offset"]})')
        else:
            value = psnr_rgb(path('web-dropped-image.png'), path('voxview-dropped.png'))
            print(f'packed.vxl dropped on the page, memory 11M (a level image, read by parts): PSNR {value:.2f} dB '
                  f'against voxview, first picture after {report["first_picture_ms"]:.0f} ms')
            if value < MIN_PSNR:
                failures.append(f'packed.vxl dropped on the page, memory 11M: PSNR {value:.2f} dB < {MIN_PSNR}')

        # Damaged files reaching the page (served as they are, without share, by ranges) are refused with their
        # names: cut short by the first bytes' checks, overwritten by the draw checks of the first level or of
        # full detail.
        folder = path('share-packed-vxl')

        def expect_refused(what, query, expected, handler=RangeHandler):
            """The page opened with `query` (served from `folder`) fails with a message holding `expected`."""
            server = Server(folder, handler)
            try:
                report = capture(f'{server.url}index.html?size={SIZE}&{query}', path('refused.png'))
            finally:
                server.close()
            if expected not in report.get('error', ''):
                failures.append(f'{what} in the page: {report}')
            else:
                print(f'{what} in the page: {report["error"]}')
            return report.get('error', '')

        shutil.copy(path('float32.vxl'), folder)
        expect_refused('a file changed on the server while fetched', 'file=changed.vxl', 'changed on the server',
                       ChangingHandler)
        refused = {}
        for name in ('damaged.vxl', 'ordb-damaged.vxl', 'vert-damaged.vxl'):
            shutil.copy(path(name), folder)
            refused[name] = expect_refused(name, f'file={name}', name)
        # The same damage drawn from a level image (11M holds the 20k set's level 0 without its streamline tables, not
        # the whole file): refused as well, naming the byte of the file it lies in, not the image's.
        for name in ('ordb-damaged.vxl', 'vert-damaged.vxl'):
            byte = re.search(r'at byte \d+', refused[name])
            expect_refused(f'{name} as a level image', f'file={name}&memory=11M',
                           f'{name}: {byte.group(0)}: ' if byte else 'no byte named without the image')
        shutil.copy(path('damaged.vxlz'), folder)
        expect_refused('damaged.vxlz', 'file=damaged.vxlz', 'damaged.vxlz: at byte')

        # A GPU memory budget that is not a size, and one that not even the coarsest level fits: refused, saying so.
        for budget, expected in (('lots', "'lots' is not a size of memory"), ('1K', 'does not fit the GPU memory budget')):
            expect_refused(f'GPU budget {budget}', f'file=packed.vxl&gpu={budget}', expected)
        # A page memory that not even the coarsest level's image fits: refused, saying so.
        expect_refused('page memory 4K', 'file=packed.vxl&memory=4K', 'coarsest level of detail')
        expect_refused('page memory lots', 'file=packed.vxl&memory=lots', "'lots' is not a size of memory")

    for f in failures:
        print('FAILED: ' + f)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
