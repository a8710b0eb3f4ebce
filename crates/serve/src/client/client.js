// raykit serve web client: shows the server's JPEG frames, sends camera input.
// Wire protocol: crates/serve/PROTOCOL.md.
(function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const canvas = $('view'), ctx = canvas.getContext('2d');
  const statsEl = $('stats'), errorEl = $('error');

  // Test hooks, updated live.
  const R = window.raykit = { frames: 0, lastHeader: null, clientId: null, errors: [], ws: null };

  let ws = null, state = 'connecting', backoff = 1000;
  let hello = null, sceneName = '', triangles = 0;
  let limits = { max_inputs_per_second: 60 };
  let seq = 0;
  let pending = [];        // [seq, performance.now() when sent], oldest first
  const latencies = [];    // last 64 client-measured input-to-frame latencies (ms)
  const sentTimes = [];    // send times of inputs in the last second (rate limit)
  const drawTimes = [];    // draw times of frames in the last second (client fps)
  let errorTimer = 0;

  // ---- connection -------------------------------------------------------
  function wsUrl() {
    const u = new URL('ws', location.href);
    u.protocol = u.protocol === 'https:' ? 'wss:' : 'ws:';
    u.search = '';
    u.hash = '';
    const token = new URLSearchParams(location.search).get('token');
    if (token !== null) u.searchParams.set('token', token);
    return u.href;
  }

  function connect() {
    state = 'connecting';
    const sock = new WebSocket(wsUrl());
    sock.binaryType = 'arraybuffer';
    ws = R.ws = sock;
    pending = [];
    sock.onopen = () => { state = 'connected'; backoff = 1000; };
    sock.onmessage = (ev) => {
      if (typeof ev.data === 'string') onText(ev.data); else onFrame(sock, ev.data);
    };
    sock.onclose = (ev) => {
      if (ws !== sock) return;
      state = 'disconnected' + (ev.code && ev.code !== 1006 ? ' (' + ev.code + (ev.reason ? ' ' + ev.reason : '') + ')' : '');
      setTimeout(connect, backoff);
      backoff = Math.min(backoff * 2, 10000);
    };
  }

  function onText(text) {
    let m;
    try { m = JSON.parse(text); } catch (e) { console.warn('raykit: bad message', text); return; }
    if (m.type === 'hello') {
      hello = m;
      R.clientId = m.client;
      if (m.limits) limits = m.limits;
      sceneName = m.scene; triangles = m.triangles;
      if (m.quality) { $('quality').value = m.quality; $('qval').textContent = m.quality; }
      const res = $('resolution');
      for (const o of res.options) {
        const [w, h] = o.value.split('x').map(Number);
        o.disabled = (limits.max_width && w > limits.max_width) || (limits.max_height && h > limits.max_height);
      }
      if (m.full) {
        const v = m.full[0] + 'x' + m.full[1];
        if (![...res.options].some((o) => o.value === v)) res.add(new Option(v, v));
        res.value = v;
      }
    } else if (m.type === 'scene') {
      sceneName = m.scene; triangles = m.triangles;
    } else if (m.type === 'error') {
      showError(m.message);
    }
  }

  function showError(msg) {
    console.warn('raykit:', msg);
    R.errors.push(msg);
    if (R.errors.length > 100) R.errors.shift();
    errorEl.textContent = String(msg);
    errorEl.classList.remove('hidden');
    clearTimeout(errorTimer);
    errorTimer = setTimeout(() => errorEl.classList.add('hidden'), 3000);
  }

  // ---- frames -----------------------------------------------------------
  async function onFrame(sock, buf) {
    let header = null;
    try {
      const dv = new DataView(buf);
      const len = dv.getUint32(0, true);
      header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, len)));
      const bitmap = await createImageBitmap(new Blob([new Uint8Array(buf, 4 + len)], { type: 'image/jpeg' }));
      if (canvas.width !== bitmap.width || canvas.height !== bitmap.height) {
        canvas.width = bitmap.width; canvas.height = bitmap.height;
        fit();
      }
      ctx.drawImage(bitmap, 0, 0);
      bitmap.close();
      R.frames++;
      R.lastHeader = header;
      const now = performance.now();
      drawTimes.push(now);
      // Latency of every input this frame shows.
      while (pending.length && pending[0][0] <= header.input_seq) {
        latencies.push(now - pending.shift()[1]);
        if (latencies.length > 64) latencies.shift();
      }
    } catch (e) {
      console.warn('raykit: frame not shown', e);
      if (header) R.lastHeader = header;
    }
    // Ack after drawing (or failing), so the stream never stalls.
    if (header && sock.readyState === WebSocket.OPEN) {
      sock.send(JSON.stringify({ type: 'ack', frame: header.frame }));
    }
  }

  // Size the canvas in CSS pixels: as large as the window allows, same aspect as the frame.
  function fit() {
    const w = canvas.width || 16, h = canvas.height || 9;
    const s = Math.min(innerWidth / w, innerHeight / h);
    canvas.style.width = Math.floor(w * s) + 'px';
    canvas.style.height = Math.floor(h * s) + 'px';
  }
  addEventListener('resize', fit);
  fit();

  // ---- sending ----------------------------------------------------------
  function open() { return ws && ws.readyState === WebSocket.OPEN; }

  // Room for another input under the server's per-second limit (10% margin)?
  function canSend() {
    const now = performance.now();
    while (sentTimes.length && now - sentTimes[0] > 1000) sentTimes.shift();
    const max = Math.max(1, Math.floor((limits.max_inputs_per_second || 60) * 0.9));
    return sentTimes.length < max;
  }

  // Send an input with a fresh seq; returns false when not sent.
  function send(msg, force) {
    if (!open() || (!force && !canSend())) return false;
    msg.seq = ++seq;
    const now = performance.now();
    sentTimes.push(now);
    pending.push([seq, now]);
    if (pending.length > 1024) pending.shift();
    ws.send(JSON.stringify(msg));
    return true;
  }

  // ---- input accumulation (flushed once per animation frame) -------------
  const acc = { yaw: 0, pitch: 0, px: 0, py: 0, zoom: 1, fwd: 0, right: 0, up: 0 };
  const keys = new Set();
  let orient = null, orientSent = 0, lastTick = performance.now();

  function tick(t) {
    const dt = Math.min(t - lastTick, 100);
    lastTick = t;
    // Fly while keys are held.
    if (keys.size) {
      const f = 0.01 * (dt / 16.7) * (keys.has('Shift') ? 2 : 1);
      const k = (c) => (keys.has(c) ? 1 : 0);
      acc.fwd += f * (k('KeyW') - k('KeyS'));
      acc.right += f * (k('KeyD') - k('KeyA'));
      acc.up += f * (k('KeyE') - k('KeyQ'));
    }
    // Unsent deltas stay accumulated until the rate limit allows them.
    if ((acc.yaw || acc.pitch) && send({ type: 'orbit', yaw: acc.yaw, pitch: acc.pitch })) acc.yaw = acc.pitch = 0;
    if ((acc.px || acc.py) && send({ type: 'pan', x: acc.px, y: acc.py })) acc.px = acc.py = 0;
    if (acc.zoom !== 1) {
      const f = Math.min(100, Math.max(0.01, acc.zoom));
      if (send({ type: 'zoom', factor: f })) acc.zoom = 1;
    }
    if ((acc.fwd || acc.right || acc.up) && send({ type: 'fly', forward: acc.fwd, right: acc.right, up: acc.up })) {
      acc.fwd = acc.right = acc.up = 0;
    }
    if (orient && t - orientSent >= 33 && send({ type: 'orient', alpha: orient[0], beta: orient[1], gamma: orient[2] })) {
      orient = null; orientSent = t;
    }
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);

  // ---- pointer: mouse and touch -------------------------------------------
  const pointers = new Map(); // pointerId -> { x, y, pan }
  const cssHeight = () => canvas.getBoundingClientRect().height || 1;

  function centroid() {
    const ps = [...pointers.values()].slice(0, 2);
    const mx = (ps[0].x + ps[1].x) / 2, my = (ps[0].y + ps[1].y) / 2;
    return { mx, my, d: Math.hypot(ps[0].x - ps[1].x, ps[0].y - ps[1].y) || 1 };
  }

  canvas.addEventListener('pointerdown', (e) => {
    if (e.pointerType === 'mouse' && e.button !== 0 && e.button !== 2) return;
    e.preventDefault();
    canvas.focus({ preventScroll: true });
    try { canvas.setPointerCapture(e.pointerId); } catch (_) { /* ignore */ }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey });
  });

  canvas.addEventListener('pointermove', (e) => {
    const p = pointers.get(e.pointerId);
    if (!p) return;
    const h = cssHeight();
    if (pointers.size >= 2) {
      // Two fingers: pinch zoom and pan by the midpoint motion.
      const a = centroid();
      p.x = e.clientX; p.y = e.clientY;
      const b = centroid();
      acc.zoom *= a.d / b.d;
      acc.px += -(b.mx - a.mx) / h;
      acc.py += (b.my - a.my) / h;
      return;
    }
    const dx = e.clientX - p.x, dy = e.clientY - p.y;
    p.x = e.clientX; p.y = e.clientY;
    if (p.pan || (e.pointerType === 'mouse' && e.shiftKey)) {
      acc.px += -dx / h; acc.py += dy / h;
    } else {
      acc.yaw += -dx * 0.005; acc.pitch += -dy * 0.005;
    }
  });

  const release = (e) => {
    pointers.delete(e.pointerId);
    try { canvas.releasePointerCapture(e.pointerId); } catch (_) { /* ignore */ }
  };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());

  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const dy = e.deltaY * (e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? 400 : 1);
    acc.zoom *= Math.exp(dy * 0.001);
  }, { passive: false });

  // ---- keyboard fly -------------------------------------------------------
  const FLY = ['KeyW', 'KeyA', 'KeyS', 'KeyD', 'KeyQ', 'KeyE'];
  addEventListener('keydown', (e) => {
    const tag = e.target && e.target.tagName;
    if (tag === 'INPUT' || tag === 'SELECT' || e.ctrlKey || e.metaKey || e.altKey) return;
    if (e.key === 'Shift') keys.add('Shift');
    if (FLY.includes(e.code)) { keys.add(e.code); e.preventDefault(); }
  });
  addEventListener('keyup', (e) => {
    if (e.key === 'Shift') keys.delete('Shift');
    keys.delete(e.code);
  });
  addEventListener('blur', () => keys.clear());

  // ---- toolbar ------------------------------------------------------------
  const quality = $('quality');
  quality.addEventListener('input', () => { $('qval').textContent = quality.value; });
  quality.addEventListener('change', () => send({ type: 'settings', quality: Number(quality.value) }, true));
  $('resolution').addEventListener('change', (e) => {
    const [width, height] = e.target.value.split('x').map(Number);
    send({ type: 'settings', width, height }, true);
  });
  $('reset').addEventListener('click', () => {
    acc.yaw = acc.pitch = acc.px = acc.py = acc.fwd = acc.right = acc.up = 0; acc.zoom = 1;
    send({ type: 'reset' }, true);
  });

  // Device orientation mode (iOS asks for permission first).
  const orientBtn = $('orient');
  let orientOn = false;
  const onOrient = (e) => {
    if (e.alpha == null && e.beta == null && e.gamma == null) return;
    orient = [e.alpha || 0, e.beta || 0, e.gamma || 0];
  };
  orientBtn.addEventListener('click', async () => {
    if (orientOn) {
      removeEventListener('deviceorientation', onOrient);
      orientOn = false; orient = null;
    } else {
      const DOE = window.DeviceOrientationEvent;
      if (!DOE) { showError('device orientation is not available'); return; }
      if (typeof DOE.requestPermission === 'function') {
        try {
          if (await DOE.requestPermission() !== 'granted') { showError('orientation permission denied'); return; }
        } catch (err) { showError('orientation permission: ' + err); return; }
      }
      addEventListener('deviceorientation', onOrient);
      orientOn = true;
    }
    orientBtn.classList.toggle('on', orientOn);
  });

  // ---- overlay (4 Hz) -----------------------------------------------------
  function median(a) {
    if (!a.length) return NaN;
    const s = [...a].sort((x, y) => x - y), m = s.length >> 1;
    return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
  }
  const fmt = (x, d) => (Number.isFinite(x) ? x.toFixed(d) : '–');

  setInterval(() => {
    const now = performance.now();
    while (drawTimes.length && now - drawTimes[0] > 1000) drawTimes.shift();
    const h = R.lastHeader || {};
    statsEl.textContent = [
      state + (R.clientId != null ? ' · client ' + R.clientId : ''),
      'scene   ' + (sceneName || '–') + (triangles ? ' · ' + triangles.toLocaleString() + ' tris' : ''),
      'frame   ' + (h.width ? h.width + '×' + h.height + ' ' + h.stage + (h.spp > 1 ? ' ' + h.spp + 'spp' : '') : '–'),
      'fps     ' + fmt(h.fps, 1) + ' server · ' + drawTimes.length + ' drawn',
      'latency ' + fmt(median(latencies), 0) + ' ms client · ' + fmt(h.latency_ms, 0) + ' ms server',
      'rate    ' + fmt((h.bytes_per_second || 0) / 1000, 0) + ' KB/s',
      '#       ' + (h.frame != null ? h.frame : '–') +
        (h.render_ms != null ? ' · render ' + fmt(h.render_ms, 1) + ' ms · enc ' + fmt(h.encode_ms, 1) + ' ms' : ''),
    ].join('\n');
  }, 250);

  connect();
})();
