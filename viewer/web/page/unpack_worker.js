// Unpacks a .vxlz package off the page's thread (unpack_worker_main.cpp, built as voxunpack.js), as it arrives. The
// page posts {begin: {size, name}}, then {piece: ArrayBuffer} for each piece of the package in order, then {end:
// true} ({begin: {size, name, looks: false}}: no looks, the whole at once). It gets back {looks: [[level, bytes], ...]} once the package's tables are in (the levels of detail it can
// look at before the whole, coarsest first, and the bytes each needs), {level, vxl: ArrayBuffer, size} when the first
// of them is in (the .vxl of that level alone: the first `size` bytes of the buffer), the same for each finer one the
// page asks for with {look: level} after its bytes, then {vxl, size} (the whole package's .vxl) or {error: text}. One
// package a worker: the page ends the worker once it has the answer, and the module's memory goes with it.
importScripts('voxunpack.js');

let unpacker = null, pointer = 0, size = 0, received = 0, name = '', looksSent = false, looksWanted = true;
const ready = createVoxunpack().then((module) => { unpacker = module; });
let queue = Promise.resolve();  // the messages, one after the other (the module loads first)

// The .vxl the last unpack wrote in the module's in-memory file system: {vxl: its ArrayBuffer, size: its bytes at the
// start of it}, the file's own storage, handed over as it is (a copy would hold the file twice), and the file removed.
function unpackedFile() {
  const path = unpacker.UTF8ToString(unpacker._vu_unpacked() >>> 0);  // addresses past 2 GiB come back negative
  const node = unpacker.FS.lookupPath(path).node;
  const contents = node.contents && node.contents.buffer ? node.contents : new Uint8Array(node.contents || 0);
  const file = { vxl: contents.buffer, size: node.usedBytes };
  if (contents.byteOffset !== 0) file.vxl = contents.slice(0, file.size).buffer;
  unpacker.FS.unlink(path);
  return file;
}
function error() { return unpacker.UTF8ToString(unpacker._vu_error() >>> 0); }

function begin(message) {
  ({ size, name } = message);
  looksWanted = message.looks !== false;  // none for a package handed over whole
  received = 0;
  pointer = unpacker.ccall('vu_begin', 'number', ['number', 'string'], [size, name]) >>> 0;
  if (!pointer) throw new Error(`${name}: no memory to unpack this package in`);
}
function piece(bytes) {
  if (received + bytes.byteLength > size) {  // longer than it said: room for it
    size = Math.max(2 * size, received + bytes.byteLength);
    pointer = unpacker._vu_grow(size) >>> 0;
    if (!pointer) throw new Error(`${name}: no memory to unpack this package in`);
  }
  unpacker.HEAPU8.set(new Uint8Array(bytes), pointer + received);
  received += bytes.byteLength;
  const level = unpacker._vu_arrived(received);
  if (!looksWanted) return;
  if (!looksSent) {
    const looks = JSON.parse(unpacker.UTF8ToString(unpacker._vu_looks() >>> 0));
    if (looks.length > 0) {
      postMessage({ looks });
      looksSent = true;
    }
  }
  if (level > 0) look(level);
}
// A look that cannot be unpacked is left out: the whole package's unpack says what is wrong with it.
function look(level) {
  if (!unpacker._vu_unpack_level(level)) return;
  const file = unpackedFile();
  postMessage({ level, ...file }, [file.vxl]);
}
function end() {
  if (!unpacker._vu_unpack()) return postMessage({ error: error() });
  const file = unpackedFile();
  postMessage(file, [file.vxl]);
}

let failed = false;  // an error was answered: the rest of the package is not looked at
onmessage = (event) => {
  const message = event.data;
  queue = queue.then(async () => {
    await ready;
    if (failed) return;
    if (message.begin) begin(message.begin);
    else if (message.piece) piece(message.piece);
    else if (message.look) look(message.look);
    else if (message.end) end();
  }).catch((err) => {
    failed = true;
    postMessage({ error: String(err.message || err) });
  });
};
