// Appended to the unpacker module (voxunpack.js, --post-js): the folder it writes its .vxl files in (the module's
// current directory, /unpacked) keeps each file in pieces of 32 MiB, and takePieces(path) hands a file's pieces
// over and removes it. Emscripten's in-memory file system (MEMFS) keeps a file in one ArrayBuffer, which the page
// could only let go of whole, after copying all of it into its own memory: the tab held the .vxl twice at that
// moment. The page copies a piece at a time and lets each go. The folder is MEMFS's but for its files' storage;
// this Emscripten (Debian's 3.1.6) calls a file system's operations as library_fs.js and library_memfs.js show.
var UnpackPiecesFs = (() => {
  const PIECE = 32 << 20;
  const MAP_PRIVATE = 2, EINVAL = 28, ENODEV = 43, ENOMEM = 48;  // Emscripten's values
  if (!MEMFS.ops_table || typeof SYSCALLS.doMsync !== 'function')
    throw new Error('unpack_pieces_fs.js: this Emscripten\'s file system is not the one it was written for (3.1.6)');

  // Copies between a file's pieces and `bytes` (a Uint8Array), from the file's byte `position` on; bytes never
  // written read as zeros (as in a file sized past what was written), left as they are where `zeroed` says they are.
  function copy(node, position, bytes, intoFile, zeroed = false) {
    for (let done = 0; done < bytes.length;) {
      const k = Math.floor((position + done) / PIECE), at = (position + done) % PIECE;
      const n = Math.min(PIECE - at, bytes.length - done);
      if (intoFile) {
        if (!node.pieces[k]) node.pieces[k] = newPiece();
        node.pieces[k].set(bytes.subarray(done, done + n), at);
      } else if (node.pieces[k]) {
        bytes.set(node.pieces[k].subarray(at, at + n), done);
      } else if (!zeroed) {
        bytes.fill(0, done, done + n);
      }
      done += n;
    }
  }
  // A piece of zeros; where the browser has no memory for it, the write fails with ENOMEM (and the unpack says so).
  function newPiece() {
    try {
      return new Uint8Array(PIECE);
    } catch (error) {
      throw new FS.ErrnoError(ENOMEM);
    }
  }
  const asBytes = (buffer, offset, length) => new Uint8Array(buffer.buffer, buffer.byteOffset + offset, length);
  function resize(node, size) {
    node.pieces.length = Math.min(node.pieces.length, Math.ceil(size / PIECE));
    const k = Math.floor(size / PIECE);  // the bytes past the end of the last piece kept read as zeros again
    if (node.pieces[k]) node.pieces[k].fill(0, size % PIECE);
    node.usedBytes = size;
  }

  const fileStream = {
    llseek: MEMFS.stream_ops.llseek,
    read(stream, buffer, offset, length, position) {
      const n = Math.max(0, Math.min(length, stream.node.usedBytes - position));
      copy(stream.node, position, asBytes(buffer, offset, n), false);
      return n;
    },
    write(stream, buffer, offset, length, position) {
      copy(stream.node, position, asBytes(buffer, offset, length), true);
      stream.node.usedBytes = Math.max(stream.node.usedBytes, position + length);
      stream.node.timestamp = Date.now();
      return length;
    },
    allocate(stream, offset, length) {
      stream.node.usedBytes = Math.max(stream.node.usedBytes, offset + length);
    },
    // A copy in the module's memory, written back into the pieces when unmapped (msync).
    mmap(stream, address, length, position, prot, flags) {
      if (address !== 0) throw new FS.ErrnoError(EINVAL);
      const ptr = mmapAlloc(length) >>> 0;  // zeroed
      if (!ptr) throw new FS.ErrnoError(ENOMEM);
      copy(stream.node, position, HEAPU8.subarray(ptr, ptr + length), false, true);
      return { ptr, allocated: true };
    },
    msync(stream, buffer, offset, length, mmapFlags) {
      if (!FS.isFile(stream.node.mode)) throw new FS.ErrnoError(ENODEV);
      if (!(mmapFlags & MAP_PRIVATE)) fileStream.write(stream, buffer, 0, length, offset);
      return 0;
    },
  };
  const fileNode = {
    getattr: MEMFS.node_ops.getattr,
    setattr(node, attr) {
      if (attr.mode !== undefined) node.mode = attr.mode;
      if (attr.timestamp !== undefined) node.timestamp = attr.timestamp;
      if (attr.size !== undefined) resize(node, attr.size);
    },
  };
  function createNode(parent, name, mode, dev) {
    const node = MEMFS.createNode(parent, name, mode, dev);
    if (FS.isDir(node.mode)) {
      node.node_ops = dirNode;
    } else if (FS.isFile(node.mode)) {
      [node.node_ops, node.stream_ops, node.pieces] = [fileNode, fileStream, []];
    }
    return node;
  }
  const dirNode = Object.assign({}, MEMFS.ops_table.dir.node, { mknod: createNode });

  // MEMFS's write-back of a mapping first copies the mapped bytes (HEAPU8.slice): a file of pieces takes them
  // from the module's memory as they are.
  const msyncThroughCopy = SYSCALLS.doMsync;
  SYSCALLS.doMsync = (addr, stream, len, flags, offset) => {
    if (!stream.node.pieces) return msyncThroughCopy(addr, stream, len, flags, offset);
    FS.msync(stream, HEAPU8.subarray(addr, addr + len), offset, len, flags);
  };

  FS.mkdir('/unpacked');
  FS.mount({ mount: () => createNode(null, '/', 16384 | 511, 0) }, {}, '/unpacked');
  FS.chdir('/unpacked');

  // The file at `path` as {pieces: [ArrayBuffer, ...], size}: its bytes, in order, are the first `size` of the
  // pieces put end to end (the last may be longer). The file is removed: the pieces are the caller's.
  return {
    takePieces(path) {
      const node = FS.lookupPath(path).node;
      const size = node.usedBytes;
      const pieces = [];
      for (let k = 0; k * PIECE < size; ++k) pieces.push((node.pieces[k] || newPiece()).buffer);
      node.pieces = [];
      FS.unlink(path);
      return { pieces, size };
    },
  };
})();
Module['takePieces'] = UnpackPiecesFs.takePieces;
