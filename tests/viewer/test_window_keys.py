#!/usr/bin/python3
"""Keys pressed in voxview's window reach it through the X server as a user's would (XTest), past the panel's
Dear ImGui: Tab (the next region) must not move the keyboard focus into the panel, where every later key would
be kept from the window; after it, S still saves a screenshot and Esc still quits.

Usage: tests/viewer/test_window_keys.py --voxview PATH --voxlines PATH
Runs itself under xvfb-run when there is no display. Exit 0 pass, 1 fail, 77 no X server to run (xvfb-run or
libXtst missing).
"""
import argparse
import ctypes
import os
import shutil
import subprocess
import sys
import tempfile
import time


class FakeInput:
    """Key presses and pointer moves through the XTest extension (libXtst), on $DISPLAY."""

    def __init__(self):
        self.x11 = ctypes.cdll.LoadLibrary("libX11.so.6")
        self.xtst = ctypes.cdll.LoadLibrary("libXtst.so.6")
        self.x11.XOpenDisplay.restype = ctypes.c_void_p
        self.x11.XStringToKeysym.restype = ctypes.c_ulong
        self.x11.XDefaultRootWindow.restype = ctypes.c_ulong
        self.x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
        for f in (self.x11.XKeysymToKeycode, self.x11.XFlush, self.x11.XSync, self.x11.XQueryTree,
                  self.xtst.XTestFakeKeyEvent, self.xtst.XTestFakeMotionEvent):
            f.argtypes = None
        self.display = self.x11.XOpenDisplay(None)
        if not self.display:
            raise OSError("cannot open the X display " + os.environ.get("DISPLAY", "(unset)"))

    def windows(self):
        """How many top-level windows the X server has (no window manager: the programs' own)."""
        root, parent, children, count = ctypes.c_ulong(), ctypes.c_ulong(), ctypes.c_void_p(), ctypes.c_uint()
        self.x11.XQueryTree(ctypes.c_void_p(self.display), ctypes.c_ulong(self.x11.XDefaultRootWindow(self.display)),
                            ctypes.byref(root), ctypes.byref(parent), ctypes.byref(children), ctypes.byref(count))
        if children:
            self.x11.XFree(children)
        return count.value

    def move_pointer(self, x, y):
        self.xtst.XTestFakeMotionEvent(ctypes.c_void_p(self.display), -1, x, y, 0)
        self.x11.XSync(ctypes.c_void_p(self.display), 0)

    def press(self, keysym):
        code = self.x11.XKeysymToKeycode(ctypes.c_void_p(self.display), ctypes.c_ulong(self.x11.XStringToKeysym(keysym)))
        for down in (1, 0):
            self.xtst.XTestFakeKeyEvent(ctypes.c_void_p(self.display), code, down, 0)
            self.x11.XSync(ctypes.c_void_p(self.display), 0)
            time.sleep(0.1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--voxview", required=True)
    parser.add_argument("--voxlines", required=True)
    options = parser.parse_args()
    voxview = os.path.abspath(options.voxview)  # run from the scratch folder, where the window saves its pictures
    if not os.environ.get("DISPLAY"):
        if not shutil.which("xvfb-run"):
            print("xvfb-run is not installed (apt install xvfb xauth): no X server")
            return 77
        return subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 800x600x24", sys.executable] + sys.argv).returncode
    try:
        fake = FakeInput()
    except OSError as e:
        print(f"no XTest input: {e} (apt install libxtst6)")
        return 77

    with tempfile.TemporaryDirectory() as scratch:
        tck, vxl = os.path.join(scratch, "s.tck"), os.path.join(scratch, "s.vxl")
        for command in ([options.voxlines, "synth", tck, "--streamlines", "300"], [options.voxlines, "convert", tck, vxl]):
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        before = fake.windows()
        viewer = subprocess.Popen([voxview, vxl, "--size", "400x400"], cwd=scratch, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
        deadline = time.monotonic() + 120
        while fake.windows() <= before and viewer.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(2)  # the first frames
        fake.move_pointer(300, 300)  # over the picture, away from the panel: no window manager, focus follows it
        for keysym in (b"Tab", b"s", b"Escape"):
            fake.press(keysym)
            time.sleep(0.5)
        try:
            output, _ = viewer.communicate(timeout=60)
            quit_by_escape = True
        except subprocess.TimeoutExpired:
            viewer.kill()
            output, _ = viewer.communicate()
            quit_by_escape = False
        saved = [name for name in os.listdir(scratch) if name.startswith("voxview-") and name.endswith(".png")]
    print(output.strip())
    failures = []
    if not saved:
        failures.append("S after Tab saved no screenshot")
    if not quit_by_escape:
        failures.append("Esc after Tab did not quit within 60 s")
    elif viewer.returncode != 0:
        failures.append(f"voxview exited with {viewer.returncode}")
    for failure in failures:
        print("FAILED", failure)
    print("Tab, S, Esc: " + ("ok" if not failures else "FAILED"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
