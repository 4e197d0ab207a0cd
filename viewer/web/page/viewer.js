// The web viewer's page: fetches a .vxl file or a .vxlz package (?file=URL, else the one share.json names, or a file
// dropped on the page), hands its bytes to the WebAssembly viewer (voxweb.js: the project's reader, unpacker and renderer),
// and turns the panel, the mouse and the address's #view part into its settings. Nothing of the method is
// here: the voxel sort and the choice of stored orders run in the WebAssembly renderer, as in voxview.
'use strict';

(function () {
  // Steps on the way to the first picture, for benchmarks (performance.getEntriesByType('mark')).
  const mark = (step) => performance.mark('voxweb:' + step);
  mark('script');
  // The page's long tasks (50 ms and more, during which it takes no input), [start, duration] in ms, for benchmarks.
  const longTasks = [];
  try {
    new PerformanceObserver((list) => {
      for (const e of list.getEntries()) longTasks.push([e.startTime, e.duration]);
    }).observe({ type: 'longtask' });
  } catch (err) {  // a browser without them: none listed
  }
  const $ = (id) => document.getElementById(id);
  const canvas = $('canvas');
  const params = new URLSearchParams(location.search);
  // For tests and for embedding: ?size=WxH fixes the picture's size in pixels.
  const fixedSize = /^(\d+)x(\d+)$/.exec(params.get('size') || '');
  // The GPU memory budget (voxview's --gpu-memory): what is drawn at rest is the finest level of detail whose GPU
  // copy fits it. ?gpu=SIZE (512M, 2G) sets it; else a quarter of the memory the browser reports
  // (navigator.deviceMemory, at most 8 GiB), as voxview takes a quarter where the driver reports none: WebGL
  // reports no GPU memory. 1 GiB where the browser reports nothing either.
  const gpuBudget = params.get('gpu') || `${Math.round((navigator.deviceMemory || 4) * 256)}M`;
  // The most of a .vxl read by ranges (or dropped) the page holds (?memory=SIZE: 512M, 2G): a larger one is drawn
  // from its coarser levels, as a .vxl of their own that fits (a level image); at most what the WebAssembly memory
  // holds.
  const memoryParam = /^(\d+(?:\.\d+)?)([KMG]?)$/i.exec(params.get('memory') || '');
  const memoryLimit = memoryParam ? Number(memoryParam[1]) * 1024 ** ' KMG'.indexOf((memoryParam[2] || ' ').toUpperCase()) : Infinity;

  // window.voxweb.ready: resolved after the first frame of a file, rejected on its error; .complete: after the
  // first frame at full detail (the first may be drawn at a coarser level).
  let settle, settleComplete;
  window.voxweb = {
    ready: new Promise((resolve, reject) => { settle = { resolve, reject }; }),
    complete: new Promise((resolve, reject) => { settleComplete = { resolve, reject }; }),
    levelsShown: [],  // the levels drawn at rest between the first picture and full detail (a file fetched by ranges)
    // Full detail's spans in the order they were fetched ({span, distance, in_view}: vw_next_ranges), and the
    // pictures at rest shown with some of them in and a coarser level in place of the others.
    spansFetched: [],
    mixedShown: [],  // when each was shown, ms from navigation
    // A package's looks before the whole ({level, at: ms from navigation}: a level of detail alone), in order.
    looks: [],
    longTasks: () => longTasks.slice(),
  };

  function say(text, isError) {
    $('status').textContent = text;
    $('status').className = isError ? 'error' : '';
  }

  function canvasSize() {
    if (fixedSize) return [Number(fixedSize[1]), Number(fixedSize[2])];
    const ratio = window.devicePixelRatio || 1;
    return [Math.max(1, Math.round(canvas.clientWidth * ratio)), Math.max(1, Math.round(canvas.clientHeight * ratio))];
  }

  function fail(message) {
    say(message, true);
    settle.reject(new Error(message));
    settleComplete.reject(new Error(message));
  }

  createVoxweb({ canvas }).then((Module) => {
    mark('wasm ready');
    const api = {
      open: Module.cwrap('vw_open', 'number', ['number', 'number', 'string', 'number', 'number', 'number']),
      planOpen: Module.cwrap('vw_plan_open', 'string', ['number', 'number', 'number', 'string', 'number']),
      openImage: Module.cwrap('vw_open_image', 'number', ['number', 'number', 'string', 'number', 'number', 'number', 'number']),
      placement: Module.cwrap('vw_placement', 'string', []),
      filePointer: Module.cwrap('vw_file_pointer', 'number', []),
      levelRanges: Module.cwrap('vw_level_ranges', 'string', ['number', 'number']),
      showLevel: Module.cwrap('vw_show_level', 'number', ['number']),
      missingRanges: Module.cwrap('vw_missing_ranges', 'string', ['number']),
      nextRanges: Module.cwrap('vw_next_ranges', 'string', ['number', 'number']),
      show: Module.cwrap('vw_show', 'number', []),
      arrived: Module.cwrap('vw_arrived', null, []),
      error: Module.cwrap('vw_error', 'string', []),
      info: Module.cwrap('vw_info', 'string', []),
      memory: Module.cwrap('vw_memory', 'string', []),
      set: Module.cwrap('vw_set', 'number', ['string', 'string']),
      drag: Module.cwrap('vw_drag', null, ['number', 'number', 'number']),
      zoom: Module.cwrap('vw_zoom', null, ['number']),
      camera: Module.cwrap('vw_camera', 'string', []),
      setCamera: Module.cwrap('vw_set_camera', 'number', ['number', 'number', 'number', 'number', 'number', 'number']),
      draw: Module.cwrap('vw_draw', 'number', ['number', 'number', 'number']),
      drawPiece: Module.cwrap('vw_draw_piece', 'number', []),
      piecesUnderWay: Module.cwrap('vw_pieces_under_way', 'number', []),
      check: Module.cwrap('vw_check', 'number', []),
      refine: Module.cwrap('vw_refine', 'number', []),
      pending: Module.cwrap('vw_pending', 'number', []),
      upload: Module.cwrap('vw_upload', 'number', []),
      setGpuBudget: Module.cwrap('vw_set_gpu_budget', 'number', ['string']),
    };
    // The calls into the viewer of 50 ms and more, [name, start, ms] (for benchmarks: what the long tasks are).
    const slowCalls = [];
    for (const [name, call] of Object.entries(api)) {
      api[name] = (...args) => {
        const start = performance.now();
        const result = call(...args);
        const ms = performance.now() - start;
        if (ms >= 50) slowCalls.push([name, start, ms]);
        return result;
      };
    }
    window.voxweb.slowCalls = () => slowCalls.slice();
    window.voxweb.mode = () => JSON.parse(api.info()).mode;  // the mode frames are drawn in (for tests)
    // The WebAssembly memory's size and malloc's use of it, the most a package's unpacker had, and the pieces the
    // whole package's .vxl came in (for benchmarks and tests).
    let unpackerMemory = 0, unpackedPieces = 0;
    window.voxweb.memory = () => ({ wasm: Module.HEAPU8.length, unpacker: unpackerMemory,
      unpacked_pieces: unpackedPieces, ...JSON.parse(api.memory()) });
    // moving: a drag is under way (frames then come from the first picture's level of detail).
    let opened = false, dirty = false, firstFrame = true, fullDetail = false, moving = false;
    // The last frame shows the view at rest at full detail (a file fetched by ranges: possibly before its tables are in).
    let fullShown = false;
    // The whole file is in the WebAssembly memory (false while a file fetched by ranges still has some to come).
    let bytesComplete = true;
    // Fetching by ranges finishes the file after the first picture: fetchRest, set by fetchByRanges.
    let fetchRest = null;
    // Where the GPU budget draws a coarser level than full detail, fetching stops once that level is in: restLater
    // brings the rest when a setting needs it (fetchRestNow).
    let restLater = null, restPromise = null;
    // A package's look (a level of detail alone, openUnpacked) is on the screen, the whole still to come; the reader
    // has moved the view since the file was opened (the next look and the whole then keep that view).
    let lookShown = false, viewMoved = false;

    function set(key, value) {
      if (!bytesComplete && (restLater || restPromise) && needsWholeFileNow(key, String(value))) {
        // Applied once the rest is in, if this file is still open and the panel still asks for it.
        const gen = generation;
        return fetchRestNow(false).then(() => {
          if (gen === generation && bytesComplete && $(key).value === String(value)) set(key, value);
        });
      }
      if (api.set(key, String(value)) !== 0) {
        say(api.error(), true);
        if (key === 'mode') $('mode').value = JSON.parse(api.info()).mode;  // what it still draws in
      }
      if (key === 'color' || key === 'scalar' || key === 'colormap') showColouring();
      redraw();
    }

    // The colour bar of colouring by value, or the groups' colours.
    function showColouring() {
      const info = JSON.parse(api.info());
      const color = $('color').value;
      $('scalar-settings').hidden = color !== 'scalar';
      if (color === 'scalar') {
        const bar = $('colorbar').getContext('2d');
        const samples = info.scalar.samples;
        for (let x = 0; x < 256; ++x) {
          const t = (x / 255) * (samples.length - 1), i = Math.min(Math.floor(t), samples.length - 2), f = t - i;
          const c = samples[i].map((a, k) => Math.round(255 * (a + (samples[i + 1][k] - a) * f)));
          bar.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
          bar.fillRect(x, 0, 1, 12);
        }
        $('range-lo').textContent = info.scalar.range[0].toPrecision(4);
        $('range-hi').textContent = info.scalar.range[1].toPrecision(4);
      }
      $('legend').replaceChildren(...(color === 'group' ? info.groups : []).map((g) => {
        const row = document.createElement('div');
        const swatch = document.createElement('span');
        swatch.className = 'swatch';
        swatch.style.background = `rgb(${g.color.map((a) => Math.round(255 * a)).join(',')})`;
        row.append(swatch, `${g.name} (${g.streamlines.toLocaleString()})`);
        return row;
      }));
    }
    function redraw() {
      if (opened && !dirty) {
        dirty = true;
        requestAnimationFrame(frame);
      }
    }
    let piecesRun = 0;  // the frames drawn: pieces of an earlier one stop
    // More of full detail arrived while a picture was being drawn in pieces: another once that one is shown.
    let redrawAfterPieces = false;
    function redrawWhenShown() {
      if (api.piecesUnderWay()) redrawAfterPieces = true;
      else redraw();
    }
    function frame() {
      dirty = false;
      redrawAfterPieces = false;  // this frame draws what is in
      const run = ++piecesRun;
      const [w, h] = canvasSize();
      if (canvas.width !== w || canvas.height !== h) {
        canvas.width = w;
        canvas.height = h;
      }
      if (fixedSize) {
        canvas.style.width = w + 'px';
        canvas.style.height = h + 'px';
      }
      if (api.draw(w, h, moving ? 1 : 0) !== 0) return fail(api.error());
      if (api.piecesUnderWay()) return drawPieces(run);  // a picture at rest in pieces: on the canvas once complete
      shownFrame();
    }
    // A picture at rest drawn in pieces, one a task, so that the page takes input between them; a frame asked for
    // meanwhile (redraw) abandons it, and its own pieces, if any, replace these.
    function drawPieces(run) {
      setTimeout(function step() {
        if (run !== piecesRun || dirty || moving) return;
        const r = api.drawPiece();
        if (r > 1) return fail(api.error());
        if (r === 0) return setTimeout(step, 0);
        shownFrame();
      }, 0);
    }
    // The draw checks of what is on the GPU (voxview runs them beside the drawing; WebAssembly here has no other
    // thread): a slice a task, between the page's other tasks, until none are left. Resolves true then, false when
    // they refused the file (the page then fails).
    let checking = null;
    function checked() {
      if (!checking) {
        checking = new Promise((resolve) => {
          setTimeout(function step() {
            const r = api.check();
            if (r === 0) return setTimeout(step, 0);
            checking = null;
            if (r > 1) fail(api.error());
            resolve(r === 1);
          }, 0);
        });
      }
      return checking;
    }
    // The frame asked for is on the canvas.
    function shownFrame() {
      checked();
      if (JSON.parse(api.info()).mixed && !moving) window.voxweb.mixedShown.push(performance.now());
      if (redrawAfterPieces) redraw();
      const pending = api.pending();
      fullShown = fullDetail && !moving && !pending;
      if (firstFrame) {
        mark('first frame drawn');
        firstFrame = false;
        settle.resolve();
        setTimeout(afterFirstPicture, 0);  // once the first picture is on the screen
      }
      if (fullDetail && !moving) {
        if (pending) uploadSoon();
        else if (bytesComplete || restLater) done();
      }
    }
    // Full detail is on the screen and the whole file in: complete once what is drawn is checked.
    function done() {
      if (!bytesComplete && !restLater) return;  // a package's look: the whole is still to come
      checked().then((ok) => {
        if (!ok) return;
        $('progress').value = 1;
        settleComplete.resolve();
      });
    }
    // Resolves once the GPU has done what the page asked of it so far: a fence, looked at between tasks. WebGL hands
    // the GPU process its work to do later, and a call that must wait for it (a framebuffer's check, a pixel read)
    // holds the page's thread until the GPU process has caught up: after full detail's uploads, the next frame's
    // first call took 0.3-0.8 s, waiting for SwiftShader to copy the textures.
    function gpuCaughtUp() {
      const gl = canvas.getContext('webgl2');
      if (!gl || gl.isContextLost()) return Promise.resolve();
      const fence = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
      if (!fence) return Promise.resolve();
      gl.flush();
      return new Promise((resolve) => {
        (function look() {
          if (gl.isContextLost() || gl.getSyncParameter(fence, gl.SYNC_STATUS) === gl.SIGNALED) {
            if (!gl.isContextLost()) gl.deleteSync(fence);
            return resolve();
          }
          setTimeout(look, 4);
        })();
      });
    }
    // Full detail's upload, a few spans per task so that the page keeps taking input, each once the GPU has taken
    // the one before (so that no call waits for it); one frame when done, unless one was drawn meanwhile.
    let uploading = false, uploadAsked = -1;  // the file (generation) that asked while uploading: once more after it
    function uploadSoon() {
      if (uploading) {
        uploadAsked = generation;
        return;
      }
      [uploading, uploadAsked] = [true, -1];
      const gen = generation;
      const end = () => {  // more bytes came, or another file asked, meanwhile: again
        uploading = false;
        if (uploadAsked === generation) uploadSoon();
      };
      setTimeout(function step() {
        // The drag's end draws and comes back here; a file opened since has its own.
        if (moving || gen !== generation) return end();
        const r = api.upload();
        if (r > 1) { uploading = false; return fail(api.error()); }
        const info = JSON.parse(api.info());
        if (bytesComplete) $('progress').value = info.full_uploaded / Math.max(1, info.full_bytes);  // else the fetch's
        if (r === 0) return gpuCaughtUp().then(step);
        const run = piecesRun;
        gpuCaughtUp().then(() => {
          // A frame drawn meanwhile (or another file) drew what is in: its own shownFrame asks for what it lacks. -2:
          // the rest waits for its bytes, nothing new; -3: the picture drawn or under way is full detail already.
          if (run !== piecesRun || gen !== generation || r < -1) return end();
          uploading = false;
          if (r === 1) redraw();  // full detail for the view: now, whatever picture is under way
          else redrawWhenShown();  // -1: more of it, the rest still coming: after the picture under way
        });
      }, 0);
    }
    // The rest of a file fetched by ranges, then full detail.
    async function afterFirstPicture() {
      if (fetchRest) {
        const rest = fetchRest, gen = generation;
        fetchRest = null;
        try {
          if (!(await rest())) return;  // another file was opened meanwhile
        } catch (err) {
          if (gen === generation) fail(err.message);
          return;
        }
        if (restLater) {  // stopped at the budget's level: what needs the rest is offered, and fetches it
          offerColourings(JSON.parse(api.info()));
          for (const o of $('mode').options) if (o.disabled) [o.disabled, o.title] = [false, o.title.replace(WAITS, FETCHES)];
          if (hashWaits()) return fetchRestNow(true);  // its settings' frame is the one at rest
          applyHash(true);  // the link's colouring, which needs no more (e.g. fixed)
        } else {
          wholeFileIn(true);
        }
      }
      if (!fullDetail) refine();
      else if (!dirty && fullShown) done();  // drawn at full detail already: no frame more (SwiftShader: seconds)
      else if (!dirty && api.piecesUnderWay() && !api.pending()) return;  // under way at full detail: done when shown
      else redraw();
    }
    // The whole file is in: what waited for it is offered, and (withLink) what the address asked of it applied.
    function wholeFileIn(withLink) {
      bytesComplete = true;
      offerColourings(JSON.parse(api.info()));
      for (const o of $('mode').options) [o.disabled, o.title] = [false, o.title.replace(WAITS, '').replace(FETCHES, '')];
      if (withLink) applyHash(true);
    }
    // Fetches the rest of a file that stopped at the budget's level (once, however many settings ask), then
    // wholeFileIn; forLink: the address asked for a setting that reads it. A failed fetch can be asked for again.
    function fetchRestNow(forLink) {
      if (!restPromise) {
        const bring = restLater, gen = generation;
        restLater = null;
        say($('status').textContent + '\nfetching the rest of the file');
        restPromise = (async () => {
          try {
            if (await bring()) wholeFileIn(forLink);
          } catch (err) {
            if (gen !== generation) return;
            [restLater, restPromise] = [bring, null];
            if (forLink) fail(err.message);  // the link's picture cannot be drawn
            else say(err.message, true);
          }
        })();
      }
      return restPromise;
    }
    // False when it failed (and said why).
    function refine() {
      if (api.refine() !== 0) {
        fail(api.error());
        return false;
      }
      fullDetail = true;
      const info = JSON.parse(api.info());
      const first = info.first_level + info.level_offset;
      const why = info.full_level > 0 ? `, the finest whose copy fits the GPU memory budget of ${gpuBudget} (?gpu= sets it)`
        : info.image ? `, the finest the page's memory holds of this file (?memory= sets it)` : '';
      say($('status').textContent + `\nfirst picture at level ${first} (1/${8 ** first} of the streamlines); ` +
          `${atRestName(info)} follows${why}`);
      redraw();
      return true;
    }

    // What is drawn at rest: full detail, or the level the GPU budget or the page's memory allows.
    function atRestName(info) {
      const level = info.full_level + info.level_offset;
      return level === 0 ? 'full detail' : `level ${level}`;
    }

    // The view in the address: #az=..&el=..&distance=..&target=x,y,z&mode=..&opacity=..&color=..
    function viewHash() {
      const c = JSON.parse(api.camera());
      const h = new URLSearchParams();
      h.set('az', c.az.toFixed(2));
      h.set('el', c.el.toFixed(2));
      h.set('distance', c.distance.toPrecision(6));
      h.set('target', c.target.map((x) => x.toPrecision(7)).join(','));
      h.set('mode', $('mode').value);
      h.set('opacity', $('opacity').value);
      h.set('color', $('color').value);
      if ($('color').value === 'scalar') {
        h.set('scalar', $('scalar').value);
        h.set('colormap', $('colormap').value);
      }
      return '#' + h.toString();
    }
    // Settings that read the voxline and streamline tables, which a file fetched by ranges brings last: colouring
    // by value or group, and the unsorted mode (it draws in the streamlines' order).
    function needsWholeFile(key, value) {
      // A level image has no streamline tables to wait for: what reads them is refused at once, saying why.
      if (window.voxweb.info && window.voxweb.info.image) return false;
      return key === 'color' || key === 'scalar' || key === 'colormap' || (key === 'mode' && value === 'unsorted');
    }
    // What a setting asks of the file now: the voxline and streamline tables, for the unsorted mode and colouring by
    // value or group.
    function needsWholeFileNow(key, value) {
      return (key === 'mode' && value === 'unsorted') || (key === 'color' && (value === 'scalar' || value === 'group'));
    }
    // Whether the address asks for a setting that needs the whole file.
    function hashWaits() {
      const h = new URLSearchParams(location.hash.slice(1));
      return ['mode', 'color'].some((key) => h.has(key) && needsWholeFileNow(key, h.get(key)));
    }
    // afterWholeFile: only the settings that waited for the whole file (the view may have moved since).
    function applyHash(afterWholeFile) {
      const h = new URLSearchParams(location.hash.slice(1));
      if (afterWholeFile !== true && !bytesComplete && restLater && hashWaits()) fetchRestNow(true);
      for (const key of ['mode', 'opacity', 'color', 'scalar', 'colormap']) {
        if (!h.has(key)) continue;
        const waits = needsWholeFile(key, h.get(key));
        if (afterWholeFile === true ? !waits : waits && !bytesComplete) continue;
        $(key).value = h.get(key);
        set(key, h.get(key));
      }
      if (afterWholeFile !== true && h.has('az') && h.has('el') && h.has('distance') && h.has('target')) {
        const t = h.get('target').split(',').map(Number);
        if (api.setCamera(Number(h.get('az')), Number(h.get('el')), Number(h.get('distance')), t[0], t[1], t[2]) !== 0)
          say(api.error(), true);
      }
      $('opacity-value').textContent = $('opacity').value;
      if (afterWholeFile !== true) redraw();  // after it, only a setting applied (set) asks for a frame
    }

    // A package unpacked in `worker` (unpack_worker.js) as its bytes arrive: add(Uint8Array) hands each piece over
    // (copied), end() says all are in and resolves with the answer, {pieces: [ArrayBuffer, ...], size} (the .vxl: the
    // first `size` bytes of the pieces end to end) or {error: text}. Where its first bytes hold a level of detail to
    // look at while the rest arrives, onLook(level, {pieces, size}) gets it (and each finer one askFiner asks for)
    // before the end; onLook null: no looks. A package opened since ends the one before ({stale: true}); so does
    // cancel().
    let unpacking = null;  // the package being unpacked
    function unpackInWorker(worker, size, name, onLook) {
      if (unpacking) unpacking.cancel();
      let answer;
      const whole = new Promise((resolve) => {
        answer = (message) => {
          worker.terminate();
          if (unpacking === self) unpacking = null;
          resolve(message);
        };
      });
      let looks = null, asked = 0;  // the levels the worker can unpack alone ([level, bytes], coarsest first)
      const self = {
        add(value) {
          const piece = value.slice().buffer;
          worker.postMessage({ piece }, [piece]);
        },
        // `received` of the package's `declared` bytes are in: while a quarter or more is still to come (a slow
        // network: the whole is a while off), the finest level whose bytes are in and that is finer than those shown.
        askFiner(received, declared) {
          if (!looks || !(declared > 0) || received > 0.75 * declared) return;
          let finest = 0;
          for (const [level, bytes] of looks.slice(1)) if (bytes <= received && level < asked) finest = level;
          if (finest > 0) worker.postMessage({ look: (asked = finest) });
        },
        end() {
          worker.postMessage({ end: true });
          return whole;
        },
        cancel() { answer({ stale: true }); },
      };
      unpacking = self;
      worker.onmessage = (event) => {
        if (event.data.looks) [looks, asked] = [event.data.looks, event.data.looks[0][0]];
        else if (event.data.level && !event.data.error) onLook(event.data.level, event.data);
        else answer(event.data);
      };
      worker.onerror = (event) => {
        event.preventDefault();
        answer({ error: `${name}: the unpacker could not run (${event.message || 'unpack_worker.js did not load'})` });
      };
      worker.postMessage({ begin: { size, name, looks: onLook !== null } });
      return self;
    }
    // Lets an unpacked file's buffer go now (a transfer detaches it, and a closed channel drops the message it
    // holds) rather than at the collector's next full collection: a page that makes little JavaScript garbage may not
    // have one for minutes, and the buffer is as large as the file the page keeps in the WebAssembly memory.
    function discard(buffer) {
      if (!(buffer instanceof ArrayBuffer) || buffer.byteLength === 0) return;
      const channel = new MessageChannel();
      channel.port1.postMessage(null, [buffer]);
      channel.port1.close();
      channel.port2.close();
    }
    // A worker for the unpacker; null where the browser has none or refuses it (a page opened from the disk).
    function unpackWorker() {
      try {
        return typeof Worker === 'function' ? new Worker('unpack_worker.js') : null;
      } catch (error) {
        return null;
      }
    }

    // Whether a file's first bytes are a .vxlz package's magic (\x89VXZ\r\n\x1a\n).
    const PACKAGE_MAGIC = [0x89, 0x56, 0x58, 0x5a, 0x0d, 0x0a, 0x1a, 0x0a];
    const isPackage = (bytes) => bytes.length >= 8 && PACKAGE_MAGIC.every((b, i) => bytes[i] === b);

    // The whole file's bytes (from Module._malloc; the viewer frees them). A package is unpacked first, in a
    // worker (unpack_worker.js), so that the page keeps drawing and taking input; where the browser has no
    // workers, by the viewer itself on this thread, the page saying so before it begins.
    async function openBytes(pointer, size, name, target) {
      const t0 = performance.now();
      if (isPackage(Module.HEAPU8.subarray(pointer, pointer + 8))) {
        say(`${name}: unpacking the package`);
        const worker = unpackWorker();
        if (worker) {
          const package_ = unpackInWorker(worker, size, name, null);  // in memory whole: no looks first
          package_.add(Module.HEAPU8.subarray(pointer, pointer + size));
          Module._free(pointer);
          return openUnpacked(await package_.end(), name, target, t0);
        }
        await new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 0)));
        if (!current(target)) return Module._free(pointer);
      }
      const [w, h] = canvasSize();
      if (api.open(pointer, size, name, w, h, 1) !== 0) return fail(api.error());
      mark('opened');
      shown(name, t0);
    }
    // A package streamed into the unpacker as it arrives (`first`: its first piece), or null when `first` is not a
    // package's or the browser has no workers (the package is then read whole and opened by openBytes). Its looks
    // (levels of detail alone, from its first bytes) are shown while the rest arrives.
    function streamedPackage(target, first, declared) {
      if (!isPackage(first)) return null;
      const worker = unpackWorker();
      if (!worker) return null;
      const t0 = performance.now();
      say(`${target.name}: unpacking the package as it arrives`);
      return unpackInWorker(worker, Math.max(declared, first.length), target.name, (level, file) => {
        openUnpacked(file, target.name, target, t0, level);
      });
    }
    // What the unpacker answered (unpackInWorker): the package's .vxl opened, or its error said. level > 0: a look,
    // that level of detail alone, drawn with its opacity (package-level) until a finer look or the whole replaces it
    // in the view, and with the panel's choices, the reader has moved to meanwhile.
    // One after another (a look's copy may still be under way when the next arrives).
    let unpackedOpening = Promise.resolve();
    function openUnpacked(...args) {
      const target = args[2];
      unpackedOpening = unpackedOpening.then(() => openUnpackedNow(...args)).catch((err) => {
        if (current(target)) fail(String(err.message || err));
      });
      return unpackedOpening;
    }
    // Copies an unpacked .vxl's `size` bytes, its pieces end to end, into the WebAssembly memory at `pointer`, a
    // piece a task (the 1M set's 745 MiB at once held the page for half a second), letting each go once copied (the
    // pieces and the copy together hold the file and a piece, not the file twice). False when another file was
    // opened meanwhile; throws when the pieces hold fewer bytes.
    async function copyPieces(pieces, size, pointer, target) {
      let at = 0;
      for (let k = 0; k < pieces.length && at < size; ++k) {
        if (k > 0) {
          await new Promise((resolve) => setTimeout(resolve, 0));
          if (!current(target)) return false;
        }
        const n = Math.min(pieces[k].byteLength, size - at);
        Module.HEAPU8.set(new Uint8Array(pieces[k], 0, n), pointer + at);
        discard(pieces[k]);
        at += n;
      }
      if (at < size) throw new Error(`${target.name}: the unpacker handed over ${at} of the ${size} bytes of its .vxl`);
      return true;
    }
    async function openUnpackedNow(answer, name, target, t0, level = 0) {
      const pieces = answer.pieces || [];
      if (!current(target) || answer.stale) return pieces.forEach(discard);
      if (answer.error !== undefined) {
        // A package refused after a look: that picture came from bytes the refusal says are damaged.
        if (lookShown) [opened, canvas.style.visibility] = [false, 'hidden'];
        return fail(answer.error);
      }
      if (level === 0 && lookShown) mark('whole unpacked');
      else mark(level > 0 ? 'look unpacked' : 'unpacked');
      unpackerMemory = Math.max(unpackerMemory, answer.memory || 0);
      if (level === 0) unpackedPieces = pieces.length;
      const size = answer.size;
      let pointer;
      try {
        pointer = allocate(size, name);
      } catch (error) {
        pieces.forEach(discard);
        return fail(error.message);
      }
      let copied = false;
      try {
        copied = await copyPieces(pieces, size, pointer, target);
      } finally {
        pieces.forEach(discard);  // those not copied
        if (!copied) Module._free(pointer);
      }
      if (!copied) return;
      const camera = lookShown && viewMoved ? JSON.parse(api.camera()) : null;
      // What the reader chose in the panel while a look was shown stays chosen.
      const panel = lookShown ? ['mode', 'color', 'opacity'].map((key) => [key, $(key).value]) : [];
      const [w, h] = canvasSize();
      if (api.open(pointer, size, name, w, h, 1) !== 0) return fail(api.error());
      if (level > 0 && api.set('package-level', String(level)) !== 0) return fail(api.error());
      if (camera && camera.target)
        api.setCamera(camera.az, camera.el, camera.distance, camera.target[0], camera.target[1], camera.target[2]);
      bytesComplete = level === 0;  // a look waits for the whole for what reads it (unsorted, values, groups)
      lookShown = level > 0;
      mark(level > 0 ? 'look opened' : 'opened');
      if (level > 0) window.voxweb.looks.push({ level, at: performance.now() });
      shown(name, t0, level);
      for (const [key, value] of panel) {
        const option = key === 'opacity' ? null : [...$(key).options].find((o) => o.value === value);
        if (key !== 'opacity' && (!option || option.disabled)) continue;
        $(key).value = value;
        if (key === 'opacity') $('opacity-value').textContent = value;
        set(key, value);
      }
    }
    // The file is open and its first picture's renderer made: the panel, then the first frame.
    function shown(name, t0, level = 0) {
      opened = true;
      canvas.style.visibility = '';
      firstFrame = true;  // its first frame starts the rest (afterFirstPicture)
      fullShown = false;
      const info = JSON.parse(api.info());
      window.voxweb.info = info;
      fullDetail = info.full_detail;
      const drawnFrom = info.level_offset === 0 ? 'drawn without its streamline tables'
        : `drawn from level ${info.level_offset} (about 1/${8 ** info.level_offset} of them)`;
      $('info').textContent = info.image
        ? `${info.streamlines.toLocaleString()} streamlines, ${drawnFrom}: the file is larger than the page holds; ` +
          `${info.vertices.toLocaleString()} of its ${info.file_vertices.toLocaleString()} vertices, ${info.voxels.toLocaleString()} voxels`
        : `${info.streamlines.toLocaleString()} streamlines, ` +
          `${info.points.toLocaleString()} points, ${info.voxels.toLocaleString()} voxels`;
      $('mode').replaceChildren(...info.modes.map((m) => {
        const o = document.createElement('option');
        o.value = m.name;
        o.textContent = m.name;
        o.title = m.description;
        o.disabled = !bytesComplete && needsWholeFile('mode', m.name);
        if (o.disabled) o.title += WAITS;
        return o;
      }));
      $('mode').value = 'axis';
      for (const o of [...$('color').options]) if (o.value === 'scalar' || o.value === 'group') o.remove();
      if (bytesComplete) offerColourings(info);
      const seconds = ((performance.now() - t0) / 1000).toFixed(2);
      if (level > 0) say(`${name}: level ${level} of the package (${info.streamlines.toLocaleString()} streamlines, ` +
                         `1/${8 ** level} of them) in ${seconds} s; the rest is arriving`);
      else say(`${name}: opened in ${seconds} s`);
      applyHash();
    }

    // Colouring by value or by group where the file has them (they read the whole file).
    function offerColourings(info) {
      for (const o of [...$('color').options]) if (o.value === 'scalar' || o.value === 'group') o.remove();
      if (info.values.length) $('color').add(new Option('value', 'scalar'));
      if (info.groups.length > 1) $('color').add(new Option('group', 'group'));
      $('scalar').replaceChildren(...info.values.map((name) => new Option(name, name)));
    }

    // Fetching by HTTP Range requests: the header and section table, what the reader needs to open the file,
    // the first picture's level of detail, then the rest (.vxl spec §5.12: a level is a prefix of every voxel's
    // block and its own orders, so it is many small ranges, asked for many at a time).
    const FIRST_BYTES = 4096, RANGES_PER_REQUEST = 200, REQUEST_BYTES = 32 << 20, LEVEL_GAP = 4096, REST_PIECE = 8 << 20;
    const SPAN_BATCH = 4 << 20;  // full detail's spans fetched at a time: at least one, more while under this
    const SINGLE_RANGE_GAP = 1 << 20;  // for a server that answers one range a request
    // The finest level drawn at rest before full detail: a software WebGL draws about a million segments a second,
    // and each such picture delays full detail by its upload and its frames.
    const INTERIM_SEGMENTS = 2e6;
    // What the panel says of a mode that reads the whole file, while it is not in.
    const WAITS = ' (once the whole file is in)', FETCHES = ' (fetches the whole file)';
    let generation = 0;  // each file opened counts one: what is fetched for an older one is dropped

    // "bytes A-B/T" -> [A, B + 1, T] (T: null when unknown); null when malformed.
    function contentRange(header) {
      const m = /^bytes (\d+)-(\d+)\/(\d+|\*)$/.exec((header || '').trim());
      return m ? [Number(m[1]), Number(m[2]) + 1, m[3] === '*' ? null : Number(m[3])] : null;
    }
    // Sorted [begin, end) pairs with those less than `gap` apart merged.
    function coalesce(ranges, gap) {
      const merged = [];
      for (const r of [...ranges].sort((a, b) => a[0] - b[0])) {
        const last = merged[merged.length - 1];
        if (last && r[0] <= last[1] + gap) last[1] = Math.max(last[1], r[1]);
        else merged.push([r[0], r[1]]);
      }
      return merged;
    }
    function indexOf(bytes, needle, from) {
      search: for (let i = from; i + needle.length <= bytes.length; ++i) {
        for (let k = 0; k < needle.length; ++k) if (bytes[i + k] !== needle[k]) continue search;
        return i;
      }
      return -1;
    }
    // Where a response's body goes, a chunk at a time as it arrives, straight into the file's buffer (a body is
    // never held whole: a page fetching a large file in 32 MiB requests would otherwise hold them until collected).
    // Each sink checks a part's place in the file before writing a byte of it; end() gives the parts written,
    // [[begin, end, the file's size or null], ...].
    // A level image's buffer takes only some of the file's bytes, each where target.place says ([[begin, end, at],
    // ...] sorted: the file's bytes [begin, end) to `at`): the others (between ranges merged into one request) are
    // dropped.
    function copyInto(target, at, bytes) {
      const place = target.place;
      if (!place) return Module.HEAPU8.set(bytes, target.pointer + at);
      const end = at + bytes.length;
      let lo = 0, hi = place.length;
      while (lo < hi) {
        const mid = (lo + hi) >> 1;
        if (place[mid][1] <= at) lo = mid + 1;
        else hi = mid;
      }
      for (let i = lo; i < place.length && place[i][0] < end; ++i) {
        const [begin, until, to] = place[i];
        const from = Math.max(begin, at), stop = Math.min(until, end);
        if (from < stop) Module.HEAPU8.set(bytes.subarray(from - at, stop - at), target.pointer + to + (from - begin));
      }
    }
    // The whole file (a 200 answer), or one range ([begin, end) of `total`).
    function rangeSink(target, begin, end, total, wrong) {
      let at = begin;
      return {
        add(bytes) {
          if (at + bytes.length > end) throw new Error(wrong);
          copyInto(target, at, bytes);
          at += bytes.length;
        },
        end() {
          if (at !== end) throw new Error(wrong);
          return [[begin, end, total]];
        },
      };
    }
    // A multipart/byteranges body: each part's headers, then its bytes, found as they arrive.
    function multipartSink(target, boundary, url) {
      const marker = new TextEncoder().encode('--' + boundary), blank = new TextEncoder().encode('\r\n\r\n');
      const found = [];
      let pending = new Uint8Array(0);  // bytes not yet placed: a delimiter's or headers' start
      let part = null;  // the part whose bytes come next: {begin, end, total, at}
      let closed = false;
      const malformed = () => new Error(`${url}: a malformed multipart/byteranges answer`);
      // Takes what it can of `bytes` (the pending ones first); keeps the rest pending.
      function take(bytes) {
        let at = 0;
        while (at < bytes.length && !closed) {
          if (part) {  // the part's bytes, straight into the file
            const n = Math.min(part.end - part.at, bytes.length - at);
            copyInto(target, part.at, bytes.subarray(at, at + n));
            part.at += n;
            at += n;
            if (part.at === part.end) found.push([part.begin, part.end, part.total]), part = null;
            continue;
          }
          const delimiter = indexOf(bytes, marker, at);
          if (delimiter < 0) {  // keep what may be a delimiter's start
            at = Math.max(at, bytes.length - marker.length);
            break;
          }
          const after = delimiter + marker.length;
          if (after + 2 > bytes.length) { at = delimiter; break; }
          if (bytes[after] === 45 && bytes[after + 1] === 45) { closed = true; break; }  // "--": the closing one
          const headersEnd = indexOf(bytes, blank, after);
          if (headersEnd < 0) {
            if (bytes.length - delimiter > 1 << 16) throw malformed();
            at = delimiter;
            break;
          }
          const headers = new TextDecoder('latin1').decode(bytes.subarray(after, headersEnd));
          const r = contentRange((/content-range:([^\r\n]*)/i.exec(headers) || [])[1]);
          if (!r) throw malformed();
          checkPart(target, r[0], r[1], r[2]);
          part = { begin: r[0], end: r[1], total: r[2], at: r[0] };  // not empty: checkPart
          at = headersEnd + blank.length;
        }
        pending = bytes.slice(at);
      }
      return {
        add(bytes) {
          if (pending.length === 0) return take(bytes);
          const joined = new Uint8Array(pending.length + bytes.length);
          joined.set(pending);
          joined.set(bytes, pending.length);
          take(joined);
        },
        end() {
          if (part) throw malformed();  // cut in a part's bytes
          return found;
        },
      };
    }
    // A part's place in the file, checked before its bytes are written.
    function checkPart(target, begin, end, total) {
      if (end <= begin) throw new Error(`${target.url}: a range answer for bytes ${begin}-${end - 1}, which holds none`);
      if (end > target.size) throw new Error(`${target.url}: bytes ${begin}-${end - 1} lie past the file's end`);
      if (total !== null && total !== target.size)
        throw new Error(`${target.url} changed on the server while it was fetched (now ${total} bytes)`);
    }
    // The largest file the WebAssembly memory (32-bit, 4 GiB at most) can hold, with room for the viewer.
    const MAX_FILE_BYTES = Module._vw_max_file_bytes();
    function allocate(size, name) {
      if (size > MAX_FILE_BYTES) throw new Error(`${name}: ${size.toLocaleString()} bytes, more than the web viewer can hold (4 GiB less 256 MiB)`);
      const pointer = Module._malloc(Math.max(1, size)) >>> 0;  // an address past 2 GiB comes back negative
      if (!pointer) throw new Error(`${name}: no memory for its ${size.toLocaleString()} bytes`);
      return pointer;
    }
    // Whether `target` (a file being fetched) is still the one being opened: a file opened since drops it.
    const current = (target) => target.gen === generation;

    // Fetches `ranges` ([begin, end) pairs) of the file into its buffer: `target` = {url, name, gen, pointer, size,
    // received}. Several ranges a request (up to RANGES_PER_REQUEST and REQUEST_BYTES); the ones a server left out
    // (some answer the first range only) one at a time. False when another file was opened meanwhile.
    async function fetchRanges(target, ranges) {
      const covered = (r, got) => got.some((g) => g[0] <= r[0] && r[1] <= g[1]);
      let left = target.multipart === false ? ranges : [];
      for (let i = 0; i < ranges.length && target.multipart !== false && !target.whole;) {
        let j = i + 1, bytes = ranges[i][1] - ranges[i][0];
        while (j < ranges.length && j - i < RANGES_PER_REQUEST && bytes + ranges[j][1] - ranges[j][0] <= REQUEST_BYTES)
          bytes += ranges[j][1] - ranges[j++][0];
        const batch = ranges.slice(i, j);
        const got = await fetchBatch(target, batch);
        if (got === null) return false;
        if (batch.length > 1 && !target.whole) target.multipart = got.length > 1;
        left = left.concat(batch.filter((r) => !covered(r, got)));
        if (target.multipart === false) left = left.concat(ranges.slice(j));
        i = j;
      }
      if (target.whole) return current(target);
      // One range a request: the small ones merged, a little more fetched for far fewer requests.
      if (target.multipart === false) left = coalesce(left, SINGLE_RANGE_GAP);
      for (const r of left) {
        const got = await fetchBatch(target, [r]);
        if (got === null) return false;
        if (!target.whole && !covered(r, got)) throw new Error(`${target.url}: the server did not send bytes ${r[0]}-${r[1] - 1}`);
      }
      return current(target);
    }
    // One request: the ranges received (null when another file was opened meanwhile). A server that answers a
    // range request with the whole file (status 200, as some do past a number of ranges) gives it all at once.
    // Hands `stream` (a response's body, a dropped file's bytes) to `sink` a chunk at a time; false when another
    // file was opened meanwhile. Read into one buffer of its own where the browser lets it (a byte stream's
    // reader), so that the chunks, copied out at once, leave nothing for the collector; else chunk by chunk as the
    // browser makes them.
    async function readBody(stream, sink, target) {
      let reader, buffer = null;
      try {
        reader = stream.getReader({ mode: 'byob' });
        buffer = new ArrayBuffer(1 << 20);
      } catch (err) {
        reader = stream.getReader();
      }
      for (;;) {
        const { done, value } = await (buffer ? reader.read(new Uint8Array(buffer)) : reader.read());
        if (!current(target)) {
          reader.cancel().catch(() => {});
          return false;
        }
        if (done) return true;
        sink.add(value);
        if (buffer) buffer = value.buffer;  // handed back by the read, to be read into again
      }
    }
    async function fetchBatch(target, batch) {
      if (target.blob) return readParts(target, batch);
      const spec = batch.map((r) => `${r[0]}-${r[1] - 1}`).join(',');
      const response = await fetch(target.url, { headers: { Range: 'bytes=' + spec } });
      if (!current(target)) return null;
      if (response.status !== 206 && response.status !== 200)
        throw new Error(`${target.url}: HTTP ${response.status} to a range request`);
      const boundary = /multipart\/byteranges;\s*boundary="?([^";]+)"?/i.exec(response.headers.get('Content-Type') || '');
      let sink;
      if (response.status === 200) {
        sink = rangeSink(target, 0, target.size, target.size,
          `${target.url} changed on the server while it was fetched (its length is not ${target.size} bytes)`);
        target.whole = true;
      } else if (boundary) {
        sink = multipartSink(target, boundary[1], target.url);
      } else {
        const r = contentRange(response.headers.get('Content-Range'));
        if (!r) throw new Error(`${target.url}: a range answer without a valid Content-Range`);
        checkPart(target, r[0], r[1], r[2]);
        sink = rangeSink(target, r[0], r[1], r[2], `${target.url}: a range answer of the wrong length`);
      }
      if (!(await readBody(response.body, sink, target))) return null;
      const got = sink.end();
      for (const [begin, end] of got) target.received += end - begin;
      $('progress').value = Math.min(1, target.received / (target.total || target.size));
      return got;
    }
    // A dropped file read by parts, as a server's ranges (the ranges read, as fetchBatch gives them; null when another
    // file was opened meanwhile).
    async function readParts(target, batch) {
      for (const [begin, end] of batch) {
        const bytes = new Uint8Array(await target.blob.slice(begin, end).arrayBuffer());
        if (!current(target)) return null;
        if (bytes.length !== end - begin) throw new Error(`${target.name}: changed on the disk while it was read`);
        copyInto(target, begin, bytes);
        target.received += bytes.length;
      }
      $('progress').value = Math.min(1, target.received / (target.total || target.size));
      return batch.map(([begin, end]) => [begin, end, target.size]);
    }
    // Fetches `ranges` and tells the viewer they are in (vw_arrived); false when another file was opened meanwhile.
    async function bring(target, ranges) {
      if (!(await fetchRanges(target, ranges))) return false;
      api.arrived();
      return true;
    }
    // Fetches `ranges` into the buffer at target.pointer, then runs `check` (which may throw); the buffer is freed when
    // either throws or another file was opened meanwhile (false).
    async function fetchOrFree(target, ranges, check = () => {}) {
      let ok;
      try {
        ok = await fetchRanges(target, ranges);
        if (ok) check();
      } catch (err) {
        Module._free(target.pointer);
        throw err;
      }
      if (!ok) Module._free(target.pointer);
      return ok;
    }
    // Fetches what the reader needs to open the file (`plan`, vw_plan_open's ranges) into a buffer of the file's size,
    // and opens it; false when it failed (and said why) or another file was opened meanwhile.
    async function openFetched(target, first, plan) {
      const { name, size } = target;
      target.pointer = allocate(size, name);
      Module.HEAPU8.set(first, target.pointer);
      target.received = first.length;
      if (!(await fetchOrFree(target, plan))) return false;
      mark('tables fetched');
      const [w, h] = canvasSize();
      // From here the viewer holds the buffer (and frees it).
      if (api.open(target.pointer, size, name, w, h, 0) !== 0) return fail(api.error()), false;
      return true;
    }
    // A file larger than the page holds: its tables (`plan.image`) fetched one after another into a buffer of
    // `plan.bytes`, the level image made from them (vw_open_image), and its buffer then filled from the file where
    // vw_placement says. False as openFetched.
    async function openImage(target, first, plan, maxBytes) {
      const { name, size } = target;
      let at = 0;
      target.place = plan.image.map(([begin, end]) => [begin, end, (at += end - begin) - (end - begin)]);
      target.pointer = allocate(plan.bytes, name);
      target.total = plan.bytes;
      copyInto(target, 0, first);
      target.received = first.length;
      const tables = plan.image.filter((r) => r[1] > first.length).map((r) => [Math.max(r[0], first.length), r[1]]);
      // The image's bytes come by ranges too: a server that sent the whole file has sent them past.
      const byRanges = () => {
        if (target.whole) throw new Error(`${target.url}: the server sent the whole file to a range request; a file this large needs one that answers ranges`);
      };
      if (!(await fetchOrFree(target, tables, byRanges))) return false;
      mark('tables fetched');
      const [w, h] = canvasSize();
      // From here the viewer holds the tables' buffer (and frees it) and the image's.
      if (api.openImage(target.pointer, plan.bytes, name, size, maxBytes, w, h) !== 0) return fail(api.error()), false;
      target.pointer = api.filePointer();
      const placement = JSON.parse(api.placement());
      if (placement.error) return fail(placement.error), false;
      target.place = placement;
      target.total = target.place.reduce((n, p) => n + p[1] - p[0], 0);
      target.received = 0;
      return true;
    }
    // Opens a file by ranges, given the answer to its first request (206, the first bytes); draws the first
    // picture, and leaves fetchRest to bring the rest.
    async function fetchByRanges(target, response, t0) {
      const { name, size } = target;
      const first = new Uint8Array(await response.arrayBuffer());
      mark('first bytes');
      if (!current(target)) return;
      if (first.length === 0 || first.length > size)
        throw new Error(`${target.url}: a first range answer of ${first.length} bytes for a file of ${size}`);
      if (isPackage(first)) {  // unpacked whole, so fetched whole
        if (target.blob) throw new Error(`${name}: a package larger than the page can unpack (${size.toLocaleString()} bytes)`);
        return fetchWhole(target, await fetch(target.url));
      }
      const scratch = allocate(first.length, name);
      Module.HEAPU8.set(first, scratch);
      const maxBytes = Math.min(MAX_FILE_BYTES, memoryLimit);
      const plan = JSON.parse(api.planOpen(scratch, first.length, size, name, maxBytes));
      Module._free(scratch);
      if (plan.error) return fail(plan.error);
      if (!(await (plan.image ? openImage(target, first, plan, maxBytes) : openFetched(target, first, plan)))) return;
      mark('opened');
      if (!(await bring(target, JSON.parse(api.levelRanges(-1, LEVEL_GAP))))) return;
      mark('first level fetched');
      if (api.show() !== 0) return fail(api.error());
      mark('first level uploaded');
      bytesComplete = false;
      // The finer levels one after the other (each an eighth of the next: 1/64, 1/8 of the file...), each drawn
      // at rest as it comes; then what the level drawn at rest reads (full detail, or the finest the GPU budget
      // holds), drawn as soon as it is in; then the rest of the file (the voxline and streamline tables, the values,
      // the levels finer than the budget's). False when another file was opened meanwhile.
      fetchRest = async () => {
        const info = JSON.parse(api.info());
        for (let level = info.first_level - 1; level > info.full_level && info.level_segments[level] <= INTERIM_SEGMENTS;
          --level) {
          if (!(await bring(target, JSON.parse(api.levelRanges(level, LEVEL_GAP))))) return false;
          if (api.showLevel(level) !== 0) throw new Error(`${name}: ${api.error()}`);
          window.voxweb.levelsShown.push(level);
          const shownLevel = level + info.level_offset;
          say(`${name}: level ${shownLevel} (1/${8 ** shownLevel} of the streamlines) in; fetching the rest`);
          redraw();
          await new Promise((resolve) => setTimeout(resolve, 0));  // its frame before the next fetch
          if (!current(target)) return false;
        }
        if (!fullDetail && !refine()) return false;
        // Full detail's spans, those the view needs the nearest first, each drawn as it comes (the coarser level in
        // place of those still coming).
        for (;;) {
          const next = JSON.parse(api.nextRanges(LEVEL_GAP, SPAN_BATCH));
          if (!next.ranges.length) break;
          if (!(await bring(target, next.ranges))) return false;
          window.voxweb.spansFetched.push(...next.spans);
          if (!next.spans.some((s) => s.in_view)) continue;  // the view does not draw them (yet): nothing to upload
          const now = JSON.parse(api.info());
          say(`${name}: ${now.full_spans_in} of the ${now.full_spans} parts of ` +
              `${atRestName(info)} in, the nearest the view first`);
          uploadSoon();
        }
        // Any the renderer did not split into spans (a file fetched whole meanwhile has them all).
        if (!(await bring(target, JSON.parse(api.levelRanges(info.full_level, LEVEL_GAP))))) return false;
        const rest = () => bring(target, JSON.parse(api.missingRanges(REST_PIECE)));
        if (info.full_level === 0) return rest();
        restLater = rest;  // the budget draws a coarser level: the rest when a setting needs it
        return true;
      };
      shown(name, t0);
    }

    // Fetches `url`: by ranges where the server answers them, else whole. What fails after another file was
    // opened is not said.
    async function fetchFile(url) {
      const target = { url, name: url.split('/').pop(), gen: ++generation };
      try {
        await fetchFileInto(target);
      } catch (err) {
        if (current(target)) throw err;
      }
    }
    async function fetchFileInto(target) {
      const { url } = target;
      say('fetching ' + url);
      bytesComplete = true;
      lookShown = viewMoved = false;
      fetchRest = restLater = restPromise = null;
      window.voxweb.info = null;  // the next file's, once shown
      const t0 = performance.now();
      let probe;
      try {
        probe = await fetch(url, { headers: { Range: `bytes=0-${FIRST_BYTES - 1}` } });
      } catch (err) {  // a server that answers a range request wrongly (e.g. compressed after "identity" was asked)
        probe = await fetch(url);
      }
      if (!current(target)) return;
      if (!probe.ok) throw new Error(`${url}: HTTP ${probe.status}`);
      const range = probe.status === 206 ? contentRange(probe.headers.get('Content-Range')) : null;
      if (range && range[2] !== null && range[0] === 0) {
        target.size = range[2];
        return fetchByRanges(target, probe, t0);
      }
      if (probe.status === 206) probe.body.cancel();
      return fetchWhole(target, probe.status === 206 ? await fetch(url) : probe);
    }

    // Streams the response into the WebAssembly memory as it arrives (one copy of the file in the tab).
    async function fetchWhole(target, response) {
      if (!response.ok) throw new Error(`${target.url}: HTTP ${response.status}`);
      return openWhole(target, await readWhole(target, response.body, Number(response.headers.get('Content-Length'))));
    }
    async function dropFile(file) {
      const target = { name: file.name, gen: ++generation };
      bytesComplete = true;
      fetchRest = restLater = restPromise = null;
      window.voxweb.info = null;
      // Larger than the page holds: read by parts, as a server's ranges, and drawn from its coarser levels.
      if (file.size > Math.min(MAX_FILE_BYTES, memoryLimit)) {
        Object.assign(target, { blob: file, url: file.name, size: file.size });
        lookShown = viewMoved = false;
        return fetchByRanges(target, { arrayBuffer: () => file.slice(0, FIRST_BYTES).arrayBuffer() }, performance.now());
      }
      return openWhole(target, await readWhole(target, file.stream(), file.size));
    }
    // What readWhole read: a file in memory, or the answer of the unpacker it streamed a package into.
    async function openWhole(target, whole) {
      if (!whole) return;
      if (whole.unpacked) return openUnpacked(await whole.unpacked, target.name, target, whole.t0);
      return openBytes(whole.pointer, whole.size, target.name, target);
    }
    // Reads `stream` (a response's body, a dropped file's bytes) whole: {pointer, size} in memory from Module._malloc,
    // or for a package (where the browser has workers) {unpacked: the unpacker's answer, t0}, the package handed to
    // the unpacker as it arrives (streamedPackage); null when another file was opened meanwhile. Into the memory
    // allocated for the `declared` length while the bytes fit it; past that (a length that was not the body's, as with
    // a compressed transfer), into chunks copied together at the end. Read as the ranges are (readBody): a chunk the
    // browser made for each read would wait for the collector, the file's size of them at its peak.
    async function readWhole(target, stream, declared) {
      const { name } = target;
      const chunks = [];
      let received = 0, inMemory = 0, pointer = 0, package_ = null;
      const t0 = performance.now();
      viewMoved = lookShown = false;
      const sink = {
        add(value) {
          if (received === 0) {
            package_ = streamedPackage(target, value, declared);
            if (!package_ && declared > 0) pointer = allocate(declared, name);
          }
          if (package_) {
            package_.add(value);
            package_.askFiner(received + value.length, declared);
          } else if (pointer && chunks.length === 0 && inMemory + value.length <= declared) {
            Module.HEAPU8.set(value, pointer + inMemory);
            inMemory += value.length;
          } else {
            chunks.push(value.slice());  // the reader reads into its buffer again
          }
          received += value.length;
          if (received > MAX_FILE_BYTES) allocate(received, name);  // says why it is refused
          if (declared > 0) $('progress').value = Math.min(1, received / declared);
        },
      };
      try {
        if (!(await readBody(stream, sink, target))) throw null;
        if (package_) return { unpacked: package_.end(), t0 };
        if (chunks.length > 0 || !pointer) {
          const whole = allocate(received, name);
          if (pointer) Module.HEAPU8.copyWithin(whole, pointer, pointer + inMemory);
          if (pointer) Module._free(pointer);
          pointer = whole;
          let at = inMemory;
          for (const c of chunks) { Module.HEAPU8.set(c, whole + at); at += c.length; }
        }
      } catch (err) {
        if (pointer) Module._free(pointer);
        if (package_) package_.cancel();
        if (err === null) return null;
        throw err;
      }
      $('progress').value = 1;
      return { pointer, size: received };
    }

    async function start() {
      let url = params.get('file');
      if (!url) {
        const share = await fetch('share.json').then((r) => (r.ok ? r.json() : null)).catch(() => null);
        if (share && share.file) url = share.file;
        if (share && share.title) {
          $('title').textContent = share.title;
          document.title = share.title + ' — Voxlines';
        }
      }
      if (url) await fetchFile(url);
      else say('Drop a .vxl or .vxlz file on the page, or open it as index.html?file=URL');
    }

    // The panel.
    $('mode').onchange = () => set('mode', $('mode').value);
    $('opacity').oninput = () => { $('opacity-value').textContent = $('opacity').value; set('opacity', $('opacity').value); };
    $('color').onchange = () => set('color', $('color').value);
    $('scalar').onchange = () => set('scalar', $('scalar').value);
    $('colormap').onchange = () => set('colormap', $('colormap').value);
    for (const v of ['axial', 'inferior', 'coronal', 'posterior', 'sagittal', 'right']) {
      const b = document.createElement('button');
      b.textContent = v;
      b.onclick = () => { viewMoved = true; set('view', v); };
      $('views').appendChild(b);
    }
    $('screenshot').onclick = () => {
      const a = document.createElement('a');
      a.download = 'voxlines.png';
      a.href = canvas.toDataURL('image/png');
      a.click();
    };
    $('link').onclick = () => {
      history.replaceState(null, '', viewHash());
      if (navigator.clipboard) navigator.clipboard.writeText(location.href).catch(() => {});
      say('the address now shows this view');
    };

    // The mouse: left drag orbits, right (or shift) drag pans, the wheel zooms.
    const scale = () => canvas.height / Math.max(1, canvas.clientHeight);
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('pointerdown', (e) => {
      canvas.setPointerCapture(e.pointerId);
      moving = viewMoved = true;
      api.drag(e.button === 2 || e.shiftKey ? 2 : 1, e.offsetX * scale(), e.offsetY * scale());
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!e.buttons) return;
      api.drag(1, e.offsetX * scale(), e.offsetY * scale());  // continues the drag begun
      redraw();
    });
    canvas.addEventListener('pointerup', () => { api.drag(0, 0, 0); moving = false; redraw(); });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      viewMoved = true;
      api.zoom(-Math.sign(e.deltaY));
      redraw();
    }, { passive: false });
    window.addEventListener('resize', redraw);
    window.addEventListener('hashchange', applyHash);

    // A file dropped on the page.
    window.addEventListener('dragover', (e) => { e.preventDefault(); $('drop').style.display = 'flex'; });
    window.addEventListener('dragleave', () => { $('drop').style.display = 'none'; });
    window.addEventListener('drop', (e) => {
      e.preventDefault();
      $('drop').style.display = 'none';
      if (e.dataTransfer.files.length) dropFile(e.dataTransfer.files[0]).catch((err) => fail(err.message));
    });

    if (api.setGpuBudget(gpuBudget) !== 0) return fail(api.error());
    if (params.has('memory') && !memoryParam)
      return fail(`memory: '${params.get('memory')}' is not a size of memory (e.g. 512M, 2G)`);
    start().catch((err) => fail(err.message));
  }, (err) => fail('cannot start the viewer: ' + err));
})();
