#!/usr/bin/env python3
"""Opens a page of the web viewer in headless Chromium and writes its picture at full detail as a PNG.

    scripts/web_capture.py URL OUT.png [--timeout S] [--chromium PATH] [--drop PATH] [--page PAGE.png [--window WxH]]

The page (viewer/web/page) resolves window.voxweb.ready after its first frame (which may be drawn at a
coarser level of detail) and window.voxweb.complete after its first frame at full detail, or rejects them
with the viewer's error; this waits for both and saves the canvas. Prints one JSON line: the milliseconds
from navigation to the first picture ("first_picture_ms") and to full detail ("full_detail_ms"), the page's
JavaScript heap and what the console said.
With --drop, the page is given a file as a user drops one on it: PATH (relative to URL) is fetched and dropped on
the window once the page has loaded. With --page, the whole page (its panel beside the picture) is written too, as a
window of --window pixels (default 1100x700) shows it.
Exit 0 with the picture, 1 when the page reported an error, 2 on a browser or usage failure.

Chromium is driven over the DevTools protocol on a pipe (--remote-debugging-pipe: JSON messages ended by a
NUL byte, on file descriptors 3 and 4), which needs nothing beyond Python's standard library. WebGL2 runs on
SwiftShader, Chromium's software renderer, so no GPU and no display are needed.
"""
import argparse
import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


class DevTools:
    """The browser end of --remote-debugging-pipe."""

    def __init__(self, chromium, profile):
        to_browser_r, self._to_browser = os.pipe()
        self._from_browser, from_browser_w = os.pipe()

        def wire_pipes():  # in the child: the protocol's descriptors 3 (commands) and 4 (answers)
            # Through fresh copies: a pipe may itself be 3 or 4, and dup2 onto itself would leave it
            # closed on exec.
            commands, answers = os.dup(to_browser_r), os.dup(from_browser_w)
            os.dup2(commands, 3)
            os.dup2(answers, 4)

        self.process = subprocess.Popen(
            [chromium, '--headless', '--remote-debugging-pipe', '--no-sandbox', '--no-first-run',
             '--no-default-browser-check', '--disable-extensions', '--use-angle=swiftshader',
             '--enable-unsafe-swiftshader', '--hide-scrollbars', '--mute-audio',
             '--user-data-dir=' + profile, 'about:blank'],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            close_fds=False, preexec_fn=wire_pipes)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._next_id = 0
        self._buffer = b''
        self.events = []

    def _read_message(self, deadline):
        while b'\0' not in self._buffer:
            if time.monotonic() > deadline:
                raise TimeoutError('the browser did not answer in time')
            chunk = os.read(self._from_browser, 1 << 16)
            if not chunk:
                raise RuntimeError('the browser closed the DevTools pipe')
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b'\0', 1)
        return json.loads(message)

    def call(self, method, params=None, session=None, timeout=30):
        self._next_id += 1
        message = {'id': self._next_id, 'method': method, 'params': params or {}}
        if session:
            message['sessionId'] = session
        os.write(self._to_browser, json.dumps(message).encode() + b'\0')
        deadline = time.monotonic() + timeout
        while True:
            answer = self._read_message(deadline)
            if answer.get('id') == self._next_id:
                if 'error' in answer:
                    raise RuntimeError(f"{method}: {answer['error'].get('message')}")
                return answer.get('result', {})
            self.events.append(answer)

    def wait_event(self, method, timeout):
        deadline = time.monotonic() + timeout
        for i, e in enumerate(self.events):
            if e.get('method') == method:
                return self.events.pop(i)
        while True:
            e = self._read_message(deadline)
            if e.get('method') == method:
                return e
            self.events.append(e)

    def close(self):
        try:
            self.call('Browser.close', timeout=5)
        except (RuntimeError, TimeoutError, OSError):
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


# Waits for the page's viewer, then for its first frame and its first at full detail; gives the picture
# and the times. A read of the canvas waits for the frame before it, so each time includes its drawing.
FIRST_PICTURE = """new Promise((resolve) => {
  const canvas = () => document.getElementById('canvas');
  const failed = (e) => resolve({ error: String(e && e.message || e) });
  (function poll() {
    if (!window.voxweb) return setTimeout(poll, 10);
    window.voxweb.ready.then(() => {
      const gl = canvas().getContext('webgl2');
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      const first = performance.now();
      window.voxweb.complete.then(() => resolve({
        png: canvas().toDataURL('image/png'), first_picture_ms: first, full_detail_ms: performance.now(),
        first_level: window.voxweb.info ? window.voxweb.info.first_level : null,
        full_level: window.voxweb.info ? window.voxweb.info.full_level : null,
        level_offset: window.voxweb.info ? window.voxweb.info.level_offset : null,
        image: window.voxweb.info ? window.voxweb.info.image : null,
        points: window.voxweb.info ? window.voxweb.info.points : null,
        info_text: document.getElementById('info') ? document.getElementById('info').textContent : null,
        mode: window.voxweb.mode ? window.voxweb.mode() : null,
        levels_shown: window.voxweb.levelsShown || [],
        spans_fetched: window.voxweb.spansFetched || [],
        mixed_shown: window.voxweb.mixedShown || [],
        looks: window.voxweb.looks || [],
        marks: performance.getEntriesByType('mark').filter((m) => m.startTime <= first)
          .map((m) => [m.name.replace('voxweb:', ''), m.startTime]),
        heap_bytes: performance.memory ? performance.memory.usedJSHeapSize : null,
        memory: window.voxweb.memory ? window.voxweb.memory() : null,
        long_tasks: window.voxweb.longTasks ? window.voxweb.longTasks() : null,
        slow_calls: window.voxweb.slowCalls ? window.voxweb.slowCalls() : null }), failed);
    }, failed);
  })();
})"""


# Drops the file at DROP (fetched from the page's server) on the window, as a user's drop hands it to the page.
DROP_FILE = """fetch(DROP).then((r) => r.blob()).then((blob) => {
  const files = new DataTransfer();
  files.items.add(new File([blob], DROP.split('/').pop()));
  window.dispatchEvent(new DragEvent('drop', { dataTransfer: files, cancelable: true }));
})"""


def capture_in(browser, url, out, timeout, drop=None, on_done=None, page=None):
    """The page's report (a dict; with 'error' when the page failed) in a new tab of `browser` (a DevTools), its
    picture written to `out`; the tab is closed after, once on_done() (if given) has returned: the page is done, its
    tab still open (a benchmark samples its memory). `page`: (PATH, width, height), the whole page as a window of that
    size shows it, written to PATH once done."""
    target = browser.call('Target.createTarget', {'url': 'about:blank'})['targetId']
    try:
        session = browser.call('Target.attachToTarget', {'targetId': target, 'flatten': True})['sessionId']
        if page:
            browser.call('Emulation.setDeviceMetricsOverride', {'width': page[1], 'height': page[2],
                                                                'deviceScaleFactor': 1, 'mobile': False},
                         session=session)
        browser.call('Page.enable', session=session)
        browser.call('Runtime.enable', session=session)
        browser.events.clear()
        browser.call('Page.navigate', {'url': url}, session=session)
        browser.wait_event('Page.loadEventFired', timeout)
        if drop:
            dropped = browser.call('Runtime.evaluate', {'expression': DROP_FILE.replace('DROP', json.dumps(drop)),
                                                        'awaitPromise': True, 'timeout': timeout * 1000},
                                   session=session, timeout=timeout)
            if 'exceptionDetails' in dropped:
                return {'url': url, 'error': f'the drop of {drop} failed: {dropped["exceptionDetails"].get("text")}'}
        result = browser.call('Runtime.evaluate', {'expression': FIRST_PICTURE, 'awaitPromise': True,
                                                   'returnByValue': True, 'timeout': timeout * 1000},
                              session=session, timeout=timeout)
        console = [' '.join(str(a.get('value', a.get('description', ''))) for a in e['params'].get('args', []))
                   for e in browser.events if e.get('method') == 'Runtime.consoleAPICalled']
        if page and 'exceptionDetails' not in result and 'error' not in (result.get('result', {}).get('value') or {}):
            shot = browser.call('Page.captureScreenshot', {'format': 'png'}, session=session, timeout=timeout)
            with open(page[0] + '.part', 'wb') as f:
                f.write(base64.b64decode(shot['data']))
            os.replace(page[0] + '.part', page[0])
        if on_done:
            on_done()
    finally:
        browser.call('Target.closeTarget', {'targetId': target})
    value = result.get('result', {}).get('value') or {}
    if 'exceptionDetails' in result:
        value = {'error': result['exceptionDetails'].get('text', 'the page threw')}
    report = {'url': url, 'console': console}
    if 'error' in value:
        report['error'] = value['error']
        return report
    png = base64.b64decode(value['png'].split(',', 1)[1])
    with open(out + '.part', 'wb') as f:
        f.write(png)
    os.replace(out + '.part', out)
    report.update({'first_picture_ms': round(value['first_picture_ms'], 1),
                   'full_detail_ms': round(value['full_detail_ms'], 1), 'first_level': value['first_level'],
                   'full_level': value.get('full_level'), 'level_offset': value.get('level_offset'),
                   'image': value.get('image'), 'points': value.get('points'), 'info_text': value.get('info_text'),
                   'mode': value.get('mode'),
                   'levels_shown': value['levels_shown'], 'spans_fetched': value.get('spans_fetched', []),
                   'mixed_shown': value.get('mixed_shown', []),
                   'looks': value.get('looks', []),
                   'marks': value.get('marks', []),
                   'heap_bytes': value['heap_bytes'], 'memory': value.get('memory'),
                   'long_tasks': value.get('long_tasks'), 'slow_calls': value.get('slow_calls')})
    return report


class Browser:
    """A headless Chromium with a fresh profile, for pages opened one after another (a warm browser after the
    first); `with Browser(chromium) as b: b.capture(url, out, timeout)`."""

    def __init__(self, chromium):
        self._profile = tempfile.mkdtemp(prefix='voxweb-chromium-')
        try:
            self.devtools = DevTools(chromium, self._profile)
        except BaseException:
            shutil.rmtree(self._profile, ignore_errors=True)
            raise
        self.process = self.devtools.process

    def capture(self, url, out, timeout, drop=None, on_done=None, page=None):
        return capture_in(self.devtools, url, out, timeout, drop, on_done, page)

    def close(self):
        """Closes the browser and removes its profile."""
        self.devtools.close()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def capture(url, out, timeout, chromium, on_start=None, drop=None, on_done=None, page=None):
    """The page's report in a browser of its own (capture_in). on_start(process) is called once the browser runs
    (a benchmark samples its memory)."""
    with Browser(chromium) as browser:
        if on_start:
            on_start(browser.process)
        return browser.capture(url, out, timeout, drop, on_done, page)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('url')
    parser.add_argument('out')
    parser.add_argument('--timeout', type=float, default=120, help='seconds to wait for the first picture')
    parser.add_argument('--chromium', default=shutil.which('chromium') or 'chromium')
    parser.add_argument('--drop', help="a file (relative to URL) dropped on the page once it has loaded")
    parser.add_argument('--page', help='also the whole page, its panel beside the picture, as a PNG')
    parser.add_argument('--window', default='1100x700', help='the window the whole page is shown in (WxH pixels)')
    args = parser.parse_args()
    window = args.window.split('x')
    if len(window) != 2 or not all(w.isdigit() and int(w) > 0 for w in window):
        parser.error(f'--window {args.window}: not WxH')
    page = (args.page, int(window[0]), int(window[1])) if args.page else None
    try:
        report = capture(args.url, args.out, args.timeout, args.chromium, drop=args.drop, page=page)
        print(json.dumps(report))
        return 1 if 'error' in report else 0
    except (RuntimeError, TimeoutError, OSError) as e:
        print(json.dumps({'url': args.url, 'error': f'browser: {e}'}))
        return 2


if __name__ == '__main__':
    sys.exit(main())
