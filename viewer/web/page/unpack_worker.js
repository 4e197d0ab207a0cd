// Unpacks a .vxlz package off the page's thread (unpack_worker_main.cpp, built as voxunpack.js): the page posts
// {bytes: ArrayBuffer, name}, and gets back {vxl: ArrayBuffer} (the .vxl's bytes) or {error: text}. One package a
// worker: the page ends the worker once it has the answer, and the module's memory goes with it.
importScripts('voxunpack.js');

onmessage = async (event) => {
  const { bytes, name } = event.data;
  try {
    const unpacker = await createVoxunpack();
    const pointer = unpacker._malloc(bytes.byteLength) >>> 0;  // addresses past 2 GiB come back negative
    if (!pointer) throw new Error(`${name}: no memory to unpack this package in`);
    unpacker.HEAPU8.set(new Uint8Array(bytes), pointer);
    if (!unpacker.ccall('vu_unpack', 'number', ['number', 'number', 'string'], [pointer, bytes.byteLength, name])) {
      postMessage({ error: unpacker.UTF8ToString(unpacker._vu_error() >>> 0) });
      return;
    }
    const data = unpacker._vu_data() >>> 0;
    const vxl = unpacker.HEAPU8.slice(data, data + unpacker._vu_size()).buffer;
    postMessage({ vxl }, [vxl]);
  } catch (error) {
    postMessage({ error: String(error.message || error) });
  }
};
