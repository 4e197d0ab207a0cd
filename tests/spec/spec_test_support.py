"""What the spec tests share: running a program, damaging a file, and the Python modules the readers need."""
import os
import subprocess
import sys


def run(command):
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def flip_middle_byte(path):
    """One bit of the byte in the middle of `path` flipped: a change every checksum must catch."""
    with open(path, "r+b") as f:
        f.seek(os.path.getsize(path) // 2)
        byte = f.read(1)
        f.seek(-1, os.SEEK_CUR)
        f.write(bytes([byte[0] ^ 0x10]))


def readers_can_run():
    """True when this Python has what the spec readers import; else says what to install."""
    try:
        import nibabel, numpy, xxhash  # noqa: F401
    except ImportError as e:
        print(f"{sys.executable} lacks {e.name}: run scripts/setup (python3-nibabel, python3-numpy, python3-xxhash)")
        return False
    return True
