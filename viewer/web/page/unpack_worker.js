// Unpacks a .vxlz package off the page's thread (unpack_worker_main.cpp, built as voxunpack.js), as it arrives. The
// page posts {begin: {size, name}}, then {piece: ArrayBuffer} for each piece of the package in order, then {end:
// true} ({begin: {size, name, looks: false}}: no looks, the whole at once). It gets back {looks: [[level, bytes],
// ...]} once the package's tables are in (the levels of detail it can look at before the whole, coarsest first, and
// the bytes each needs), {level, pieces: [ArrayBuffer, ...], size, memory} when the first of them is in (the .vxl of
// that level alone: the first `size` bytes of the pieces end to end, so that the page can let each go once it has
// copied it; memory: the unpacker's), the same for each finer one the page asks for with {look: level} after its
// bytes, then {pieces, size, memory} (the whole package's .vxl) or {error: text}. One package a worker: the page ends
// the worker once it has the answer, and the module's memory goes with it.
importScripts('voxunpack.js');

let unpacker = null, pointer = 0, size = 0, received = 0, name = '', looksSent = false, looksWanted = true;
const ready = createVoxunpack().then((module) => { unpacker = module; });
let queue = Promise.resolve();  // the messages, one after the other (the module loads first)

// The .vxl the last unpack wrote: {pieces: [ArrayBuffer, ...], size, memory}, its bytes the first `size` of the pieces
// end to end, taken from the module's file system (unpack_pieces_fs.js) as they are, to be handed over; memory: the
// module's memory now, the most it has had (it never shrinks), for benchmarks.
function unpackedFile() {
  const path = unpacker.UTF8ToString(unpacker._vu_unpacked() >>> 0);  // >>> 0: addresses past 2 GiB
  return { ...unpacker.takePieces(path), memory: unpacker.HEAPU8.length };
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
  postMessage({ level, ...file }, file.pieces);
}
function end() {
  if (!unpacker._vu_unpack()) return postMessage({ error: error() });
  const file = unpackedFile();
  postMessage(file, file.pieces);
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
