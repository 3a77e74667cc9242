// gsfric 3-D view: the platform, its legs coloured by actuator force, the joint reactions as
// arrows, the joint friction as colours, and plots of F and the prismatic friction per leg.
// Reads the frames from the page's gsfric-data element (gsfric/view/data.py gives the layout);
// loads three.js from the page's own text (loadThree). Nothing is requested from a network.

const $ = (id) => document.getElementById(id);
const DATA = JSON.parse($('gsfric-data').textContent);
const LEGS = [0, 1, 2, 3, 4, 5];
const LEG_COLOURS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#9467bd', '#8c564b', '#e377c2'];
const DIVERGING = [[0.129, 0.400, 0.675], [0.573, 0.773, 0.871], [0.93, 0.93, 0.93],
  [0.957, 0.647, 0.510], [0.698, 0.094, 0.169]];      // pull (blue) .. 0 .. push (red)
const SEQUENTIAL = [[0.98, 0.95, 0.78], [0.996, 0.769, 0.31], [0.851, 0.373, 0.055],
  [0.4, 0.145, 0.024]];                                // no friction .. most friction
const REACTION_COLOURS = { E: '#1a9850', C: '#5e3c99' };
const FLAG_COLOUR = '#d62728';
const PAYLOAD_COLOUR = '#c9a227';
const DASH = { solid: [], dashed: [6, 4], dotted: [1.5, 3] };
const CAPTIONS = DATA.captions || null;   // a page of separate poses: each frame's name

// -- the data -------------------------------------------------------------------------------

function bytesOf(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

function decode(entry) {
  const bytes = bytesOf(entry.data);
  if (entry.dtype === 'float32') return new Float32Array(bytes.buffer);
  if (entry.dtype === 'int32') return new Int32Array(bytes.buffer);
  if (entry.dtype === 'uint8') return bytes;
  const codes = new Int16Array(bytes.buffer);
  const values = new Float32Array(codes.length);
  for (let i = 0; i < codes.length; i++) {
    values[i] = codes[i] === -32768 ? NaN : codes[i] * entry.scale;
  }
  return values;
}

const A = {};
for (const [name, entry] of Object.entries(DATA.arrays)) A[name] = decode(entry);
const M = DATA.frames;
const T = Float64Array.from(A.t, (v) => v + DATA.t0);

function peak(values, stride = 1) {
  let most = 0;
  for (let i = 0; i < values.length; i += stride) {
    let size = 0;
    for (let j = 0; j < stride; j++) size += values[i + j] * values[i + j];
    size = Math.sqrt(size);
    if (size > most) most = size;
  }
  return most;
}

const PEAK = {
  F: peak(A.F) || 1, R: Math.max(peak(A.R_E, 3), peak(A.R_C, 3)) || 1,
  Mfr: Math.max(peak(A.MfrE), peak(A.MfrC)) || 1, Ffr: peak(A.Ffr) || 1,
};

function vec(array, frame, leg) {
  const k = (frame * 6 + leg) * 3;
  return [array[k], array[k + 1], array[k + 2]];
}

const norm = (v) => Math.hypot(v[0], v[1], v[2]);

function fmt(value, digits = 4) {
  if (!Number.isFinite(value)) return 'n/a';
  if (value === 0) return '0';
  if (Math.abs(value) >= 10 ** digits) return value.toFixed(0);
  return String(Number(value.toPrecision(digits)));
}

function flagText(bits) {
  const names = [];
  for (const [bit, name] of Object.entries(DATA.flag_names)) if (bits & Number(bit)) names.push(name);
  return names.length ? names.join('; ') : `flag ${bits}`;
}

// -- colours --------------------------------------------------------------------------------

function ramp(stops, x) {
  if (!Number.isFinite(x)) return [0.6, 0.6, 0.6];
  const s = Math.min(Math.max(x, 0), 1) * (stops.length - 1);
  const k = Math.min(Math.floor(s), stops.length - 2);
  const w = s - k;
  return stops[k].map((a, j) => a + (stops[k + 1][j] - a) * w);
}

const forceColour = (f) => ramp(DIVERGING, 0.5 + 0.5 * f / PEAK.F);
const frictionColour = (v, most) => ramp(SEQUENTIAL, v / most);
const css = (rgb) => `rgb(${rgb.map((c) => Math.round(c * 255)).join(',')})`;
const gradient = (stops) => `linear-gradient(to right, ${stops.map(css).join(', ')})`;

// -- time and playback ----------------------------------------------------------------------

const state = { frame: 0, playing: false, speed: 1, clock: T[0], last: null, pinned: null };
const listeners = [];

function frameAt(time) {
  let lo = 0;
  let hi = M - 1;
  if (!(time > T[0])) return 0;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (T[mid] <= time) lo = mid; else hi = mid - 1;
  }
  return lo;
}

function frameName(frame) {
  if (CAPTIONS) return `${frame + 1} of ${M}: ${CAPTIONS[frame]}`;
  return `t = ${T[frame].toFixed(3)} s  (step ${A.step[frame]})`;
}

function setFrame(frame) {
  state.frame = Math.min(Math.max(frame | 0, 0), M - 1);
  if (!state.playing) state.clock = T[state.frame];
  $('slider').value = state.frame;
  const bits = A.flag[state.frame];
  $('time').textContent = frameName(state.frame);
  $('flagged').style.display = bits ? 'inline' : 'none';
  $('flagged').textContent = bits ? `flagged: ${flagText(bits)}` : '';
  for (const listener of listeners) listener(state.frame);
}

function play(on) {
  state.playing = on && M > 1;
  if (state.playing && state.frame >= M - 1) { state.clock = T[0]; setFrame(0); }
  state.last = null;
  $('play').textContent = state.playing ? 'Pause' : 'Play';
  if (state.playing) requestAnimationFrame(tick);
}

function tick(now) {
  if (!state.playing) return;
  if (state.last !== null) state.clock += (now - state.last) / 1000 * state.speed;
  state.last = now;
  if (state.clock >= T[M - 1]) {
    state.clock = T[M - 1];
    setFrame(M - 1);
    play(false);
    return;
  }
  const frame = frameAt(state.clock);
  if (frame !== state.frame) setFrame(frame);
  requestAnimationFrame(tick);
}

function hashTime() {
  const found = /(?:^#|&)t=([-+0-9.eE]+)/.exec(location.hash || '');
  const time = found ? Number(found[1]) : NaN;
  return Number.isFinite(time) ? time : null;
}

function seekToHash() {
  const time = hashTime();
  if (time === null) return;
  play(false);
  const before = frameAt(time);
  const after = Math.min(before + 1, M - 1);
  setFrame(Math.abs(T[after] - time) < Math.abs(time - T[before]) ? after : before);
}

function setUpControls() {
  $('slider').max = M - 1;
  $('play').addEventListener('click', () => play(!state.playing));
  $('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
  $('slider').addEventListener('input', (e) => { play(false); setFrame(Number(e.target.value)); });
  window.addEventListener('hashchange', seekToHash);
  window.addEventListener('keydown', (e) => {
    if (['INPUT', 'SELECT', 'BUTTON'].includes(e.target.tagName)) return;   // their own keys
    if (e.key === ' ') { e.preventDefault(); play(!state.playing); }
    if (e.key === 'ArrowRight') { play(false); setFrame(state.frame + 1); }
    if (e.key === 'ArrowLeft') { play(false); setFrame(state.frame - 1); }
  });
  const span = `t = ${fmt(T[0])} .. ${fmt(T[M - 1])} s`;
  let flagged = 0;
  for (let f = 0; f < M; f++) if (A.flag[f]) flagged++;
  $('info').textContent = (CAPTIONS ? `${M} poses, one a frame`
    : `${DATA.steps} steps, ${span}; shown as ${M} frames` +
      (DATA.fps ? ` (${fmt(DATA.fps, 3)} a second)` : '')) +
    (flagged ? `; ${flagged} frames with flagged steps (red marks)` : '');
}

// -- the plots ------------------------------------------------------------------------------

class Plot {
  // A plot of quantities per leg over time (curves: each { values (M * 6), dash }), drawn once
  // into a backing canvas; the cursor is drawn over it at every frame.
  constructor(canvas, curves, unit) {
    this.canvas = canvas;
    this.curves = curves;
    this.unit = unit;
    this.back = document.createElement('canvas');
    this.selected = null;
    canvas.addEventListener('click', (e) => this.seek(e));
    new ResizeObserver(() => this.layout()).observe(canvas);
  }

  seek(event) {
    const box = this.canvas.getBoundingClientRect();
    const x = (event.clientX - box.left) * (this.canvas.width / box.width);
    play(false);
    setFrame(frameAt(this.timeAt(x)));
  }

  timeAt(x) { return T[0] + (x - this.left) / (this.right - this.left) * (T[M - 1] - T[0]); }

  xOf(time) { return this.left + (time - T[0]) / ((T[M - 1] - T[0]) || 1) * (this.right - this.left); }

  yOf(value) { return this.bottom - (value - this.lo) / (this.hi - this.lo) * (this.bottom - this.top); }

  layout() {
    const ratio = window.devicePixelRatio || 1;
    const width = Math.max(1, Math.round(this.canvas.clientWidth * ratio));
    const height = Math.max(1, Math.round(this.canvas.clientHeight * ratio));
    this.canvas.width = this.back.width = width;
    this.canvas.height = this.back.height = height;
    this.ratio = ratio;
    this.left = 52 * ratio; this.right = width - 8 * ratio;
    this.top = 6 * ratio; this.bottom = height - 18 * ratio;
    let lo = 0; let hi = 0;
    for (const { values } of this.curves) {
      for (const v of values) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    }
    const pad = 0.06 * ((hi - lo) || 1);
    this.lo = lo - pad; this.hi = hi + pad;
    this.ticks = [...new Set([lo, 0, hi])];
    this.drawBack();
    this.draw(state.frame);
  }

  drawBack() {
    const g = this.back.getContext('2d');
    const r = this.ratio;
    g.clearRect(0, 0, this.back.width, this.back.height);
    g.font = `${11 * r}px system-ui, sans-serif`;
    g.fillStyle = '#5b6472';
    g.strokeStyle = '#d5d9e0';
    g.lineWidth = r;
    g.strokeRect(this.left, this.top, this.right - this.left, this.bottom - this.top);
    g.textAlign = 'right';
    for (const v of this.ticks) {
      g.fillText(fmt(v, 3), this.left - 4 * r, this.yOf(v) + 4 * r);
    }
    g.beginPath(); g.moveTo(this.left, this.yOf(0)); g.lineTo(this.right, this.yOf(0)); g.stroke();
    const ends = CAPTIONS ? ['1', String(M)] : [`${fmt(T[0])} s`, `${fmt(T[M - 1])} s`];
    g.textAlign = 'left'; g.fillText(ends[0], this.left, this.back.height - 4 * r);
    g.textAlign = 'right'; g.fillText(ends[1], this.right, this.back.height - 4 * r);
    g.fillStyle = FLAG_COLOUR;
    for (let f = 0; f < M; f++) {
      if (A.flag[f]) g.fillRect(this.xOf(T[f]) - r, this.bottom - 5 * r, 2 * r, 5 * r);
    }
    for (const curve of this.curves) for (const leg of LEGS) this.drawLeg(g, curve, leg);
  }

  drawLeg(g, curve, leg) {
    g.strokeStyle = LEG_COLOURS[leg];
    g.lineWidth = (this.selected === leg ? 2.5 : 1.1) * this.ratio;
    g.setLineDash((DASH[curve.dash] || []).map((d) => d * this.ratio));
    g.globalAlpha = this.selected === null || this.selected === leg ? 1 : 0.35;
    g.beginPath();
    let open = false;
    for (let f = 0; f < M; f++) {
      const v = curve.values[f * 6 + leg];
      if (!Number.isFinite(v)) { open = false; continue; }
      const x = this.xOf(T[f]); const y = this.yOf(v);
      if (open) g.lineTo(x, y); else g.moveTo(x, y);
      open = true;
    }
    g.stroke();
    g.setLineDash([]);
    g.globalAlpha = 1;
  }

  select(leg) {
    if (leg === this.selected) return;
    this.selected = leg;
    if (this.ratio) { this.drawBack(); this.draw(state.frame); }   // else at its first layout
  }

  draw(frame) {
    if (!this.ratio) return;
    const g = this.canvas.getContext('2d');
    g.clearRect(0, 0, this.canvas.width, this.canvas.height);
    g.drawImage(this.back, 0, 0);
    const x = this.xOf(T[frame]);
    g.strokeStyle = '#1d2430'; g.lineWidth = this.ratio;
    g.beginPath(); g.moveTo(x, this.top); g.lineTo(x, this.bottom); g.stroke();
    for (const { values } of this.curves) {
      for (const leg of LEGS) {
        const v = values[frame * 6 + leg];
        if (!Number.isFinite(v)) continue;
        g.fillStyle = LEG_COLOURS[leg];
        g.beginPath(); g.arc(x, this.yOf(v), 2.5 * this.ratio, 0, 2 * Math.PI); g.fill();
      }
    }
  }
}

function dashSample(dash) {
  // A short line in the curve's dash, for the plot's key.
  const gaps = (DASH[dash] || []).join(' ');
  return `<svg width="22" height="6"><line x1="0" y1="3" x2="22" y2="3" stroke="#5b6472" ` +
    `stroke-width="1.6" stroke-dasharray="${gaps}"/></svg>`;
}

function setUpPlots() {
  // One plot per entry of DATA.plots: its title and unit, a key of its curves (by dash) and of
  // the legs (by colour).
  const plots = DATA.plots.map((spec) => {
    const box = document.createElement('div');
    box.className = 'plot';
    const head = document.createElement('div');
    head.className = 'head';
    const title = document.createElement('span');
    title.textContent = `${spec.title}, ${spec.unit}`;
    const keys = document.createElement('span');
    keys.className = 'keys';
    const named = spec.curves.length > 1 ? spec.curves : [];
    keys.innerHTML = named.map((c) => `${dashSample(c.dash)}<span class="curve"></span>`).join('') +
      LEGS.map((i) => `<span style="color:${LEG_COLOURS[i]}">${i + 1}</span>`).join('');
    keys.querySelectorAll('.curve').forEach((el, k) => { el.textContent = named[k].label; });
    const canvas = document.createElement('canvas');
    head.append(title, keys);
    box.append(head, canvas);
    $('plots').append(box);
    const curves = spec.curves.map((c) => ({
      values: c.minus ? A[c.array].map((v, k) => v - A[c.minus][k]) : A[c.array], dash: c.dash }));
    return new Plot(canvas, curves, spec.unit);
  });
  listeners.push((frame) => plots.forEach((p) => p.draw(frame)));
  return plots;
}

// -- the legend -----------------------------------------------------------------------------

function setUpLegend() {
  const row = (title, stops, labels) => `<div class="row"><div>${title}</div>` +
    `<div class="bar" style="background:${gradient(stops)}"></div>` +
    `<div class="ends">${labels.map((text) => `<span>${text}</span>`).join('')}</div></div>`;
  const swatch = (colour) => `<span class="swatch" style="background:${colour}"></span>`;
  $('legend').innerHTML =
    row('actuator force F (legs)', DIVERGING, [`${fmt(-PEAK.F, 3)} N pull`, '0', `${fmt(PEAK.F, 3)} N push`]) +
    row('joint friction moment |Mfr| (balls at E<sub>i</sub>, C<sub>i</sub>)', SEQUENTIAL, ['0', `${fmt(PEAK.Mfr, 3)} N m`]) +
    row('prismatic friction |Ffr| (collars)', SEQUENTIAL, ['0', `${fmt(PEAK.Ffr, 3)} N`]) +
    `<div class="row">${swatch(REACTION_COLOURS.E)}R<sub>E</sub>: leg on platform at E<sub>i</sub><br>` +
    `${swatch(REACTION_COLOURS.C)}R<sub>C</sub>: base on leg at C<sub>i</sub><br>` +
    `arrow length &prop; |R|; the longest: ${fmt(PEAK.R, 3)} N</div>` +
    (DATA.payload.mass > 0 ? `<div class="row">${swatch(PAYLOAD_COLOUR)}payload ` +
      `${fmt(DATA.payload.mass, 3)} kg at its centre of mass</div>` : '') +
    `<div class="row" style="margin-bottom:0">${swatch(FLAG_COLOUR)}flagged step (outline, banner, plot marks)</div>`;
}

// -- three.js, from the page's own text -----------------------------------------------------

async function loadThree() {
  const blob = (text) => URL.createObjectURL(new Blob([text], { type: 'text/javascript' }));
  const core = blob($('three-core').textContent);
  const module = $('three-module').textContent.replaceAll('"./three.core.min.js"', JSON.stringify(core));
  return import(blob(module));
}

// -- the 3-D scene --------------------------------------------------------------------------

function ordered(points) {
  // The points (each [x, y, z]) in the order of their angle about their centroid.
  const c = [0, 1, 2].map((j) => points.reduce((s, p) => s + p[j], 0) / points.length);
  return points.slice().sort((a, b) => Math.atan2(a[1] - c[1], a[0] - c[0]) - Math.atan2(b[1] - c[1], b[0] - c[0]));
}

function polygon(THREE, points, colour) {
  // A filled, outlined polygon through points (a fan about their centroid).
  const loop = ordered(points);
  const c = [0, 1, 2].map((j) => loop.reduce((s, p) => s + p[j], 0) / loop.length);
  const fan = [];
  for (let k = 0; k < loop.length; k++) fan.push(...c, ...loop[k], ...loop[(k + 1) % loop.length]);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(fan, 3));
  geometry.computeVertexNormals();
  const fill = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({
    color: colour, transparent: true, opacity: 0.55, side: THREE.DoubleSide, roughness: 0.9 }));
  const line = new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints(
    loop.map((p) => new THREE.Vector3(...p))), new THREE.LineBasicMaterial({ color: '#3a4150' }));
  const group = new THREE.Group();
  group.add(fill, line);
  group.outline = line.material;
  return group;
}

function along(THREE, radius, kind) {
  // A mesh of unit length along +y from its origin: "cylinder", "cone" or "collar".
  const top = kind === 'cone' ? 0 : radius;
  const geometry = new THREE.CylinderGeometry(top, radius, 1, 20);
  geometry.translate(0, 0.5, 0);
  return new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ roughness: 0.55, metalness: 0.1 }));
}

function place(THREE, mesh, origin, direction, length) {
  // Put a mesh made by `along` at origin, pointing along the unit direction, of the length.
  mesh.position.set(...origin);
  mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), new THREE.Vector3(...direction));
  mesh.scale.set(1, Math.max(length, 1e-6), 1);
}

function arrow(THREE, radius, colour) {
  const shaft = along(THREE, radius, 'cylinder');
  const head = along(THREE, 2.4 * radius, 'cone');
  for (const part of [shaft, head]) part.material.color.set(colour);
  return { shaft, head, radius };
}

function setArrow(THREE, a, origin, force, scale) {
  const size = norm(force);
  const length = size * scale;
  const visible = Number.isFinite(length) && length > 2 * a.radius;
  a.shaft.visible = a.head.visible = visible;
  if (!visible) return;
  const u = force.map((c) => c / size);
  const head = Math.min(0.35 * length, 7 * a.radius);
  place(THREE, a.shaft, origin, u, length - head);
  place(THREE, a.head, origin.map((c, j) => c + u[j] * (length - head)), u, head);
}

function payload(THREE, size) {
  // The payload: a cube at its centre of mass (platform frame), its side growing with the cube
  // root of its mass (0.12 of the base's radius for 10 kg).
  const side = 0.12 * size * Math.cbrt(DATA.payload.mass / 10);
  const cube = new THREE.Mesh(new THREE.BoxGeometry(side, side, side),
    new THREE.MeshStandardMaterial({ color: PAYLOAD_COLOUR, roughness: 0.6, transparent: true, opacity: 0.8 }));
  cube.position.set(...DATA.payload.com);
  return cube;
}

function extent() {
  const base = DATA.base_joints;
  const radius = Math.max(...base.map((p) => Math.hypot(p[0], p[1])));
  let zMax = 0;
  for (let f = 0; f < M; f++) zMax = Math.max(zMax, A.position[3 * f + 2] || 0);
  return { radius, height: zMax };
}

function makeLegs(THREE, scene, radius) {
  return LEGS.map((leg) => {
    const parts = {
      cylinder: along(THREE, radius, 'cylinder'), rod: along(THREE, 0.55 * radius, 'cylinder'),
      collar: along(THREE, 1.45 * radius, 'collar'),
      E: new THREE.Mesh(new THREE.SphereGeometry(1.3 * radius, 20, 14), new THREE.MeshStandardMaterial({ roughness: 0.5 })),
      C: new THREE.Mesh(new THREE.SphereGeometry(1.3 * radius, 20, 14), new THREE.MeshStandardMaterial({ roughness: 0.5 })),
      RE: arrow(THREE, 0.5 * radius, REACTION_COLOURS.E), RC: arrow(THREE, 0.5 * radius, REACTION_COLOURS.C),
    };
    for (const mesh of [parts.cylinder, parts.rod, parts.collar, parts.E, parts.C]) {
      mesh.userData.leg = leg;
      scene.add(mesh);
    }
    for (const a of [parts.RE, parts.RC]) scene.add(a.shaft, a.head);
    return parts;
  });
}

function jointsAt(frame) {
  // C_i and E_i (base frame, m) at a frame: E_i = p + R(q) e_i.
  const p = [A.position[3 * frame], A.position[3 * frame + 1], A.position[3 * frame + 2]];
  let [w, x, y, z] = [0, 1, 2, 3].map((j) => A.quaternion[4 * frame + j]);
  const n = Math.hypot(w, x, y, z) || 1;
  [w, x, y, z] = [w / n, x / n, y / n, z / n];
  const top = DATA.platform_joints.map(([ex, ey, ez]) => {
    const c = [y * ez - z * ey, z * ex - x * ez, x * ey - y * ex];           // v x e
    const cc = [y * c[2] - z * c[1], z * c[0] - x * c[2], x * c[1] - y * c[0]]; // v x (v x e)
    return [ex + 2 * (w * c[0] + cc[0]) + p[0], ey + 2 * (w * c[1] + cc[1]) + p[1],
      ez + 2 * (w * c[2] + cc[2]) + p[2]];
  });
  return { base: DATA.base_joints, top, p, q: [w, x, y, z] };
}

function updateLeg(THREE, parts, leg, frame, joints, arrowScale) {
  const C = joints.base[leg];
  const E = joints.top[leg];
  const d = Math.hypot(E[0] - C[0], E[1] - C[1], E[2] - C[2]);
  const u = [0, 1, 2].map((j) => (E[j] - C[j]) / (d || 1));
  const cylinder = Math.min(DATA.legs.cylinder, d);
  place(THREE, parts.cylinder, C, u, cylinder);
  place(THREE, parts.rod, E, u.map((c) => -c), Math.min(DATA.legs.rod, d));
  place(THREE, parts.collar, C.map((c, j) => c + u[j] * (cylinder - 0.06 * d)), u, 0.06 * d);
  const colour = forceColour(A.F[frame * 6 + leg]);
  parts.cylinder.material.color.setRGB(...colour);
  parts.rod.material.color.setRGB(...colour.map((c) => 0.85 * c + 0.15));
  parts.collar.material.color.setRGB(...frictionColour(Math.abs(A.Ffr[frame * 6 + leg]), PEAK.Ffr));
  parts.E.position.set(...E);
  parts.C.position.set(...C);
  parts.E.material.color.setRGB(...frictionColour(A.MfrE[frame * 6 + leg], PEAK.Mfr));
  parts.C.material.color.setRGB(...frictionColour(A.MfrC[frame * 6 + leg], PEAK.Mfr));
  setArrow(THREE, parts.RE, E, vec(A.R_E, frame, leg), arrowScale);
  setArrow(THREE, parts.RC, C, vec(A.R_C, frame, leg), arrowScale);
  return { C, E, d };
}

function legText(leg, frame, d) {
  const F = A.F[frame * 6 + leg];
  const sense = F > 0 ? ' (push)' : F < 0 ? ' (pull)' : '';
  const bits = A.flag[frame];
  const when = CAPTIONS ? `pose ${frame + 1} of ${M}` : `t = ${T[frame].toFixed(3)} s, step ${A.step[frame]}`;
  return `leg ${leg + 1}   ${when}\n` +
    `F      ${fmt(F)} N${sense}\n` +
    `|R_E|  ${fmt(norm(vec(A.R_E, frame, leg)))} N   at E${leg + 1}, leg on platform\n` +
    `|R_C|  ${fmt(norm(vec(A.R_C, frame, leg)))} N   at C${leg + 1}, base on leg\n` +
    `|MfrE| ${fmt(A.MfrE[frame * 6 + leg])} N m   spherical joint friction\n` +
    `|MfrC| ${fmt(A.MfrC[frame * 6 + leg])} N m   universal joint friction\n` +
    `Ffr    ${fmt(A.Ffr[frame * 6 + leg])} N   prismatic friction\n` +
    `d      ${fmt(d)} m   leg length` + (bits ? `\nflagged: ${flagText(bits)}` : '');
}

class View {
  // The 3-D scene, its camera turned by dragging and zoomed by the wheel, and the legs' values
  // on hover or click.
  constructor(THREE, stage, plots) {
    this.THREE = THREE;
    this.stage = stage;
    this.plots = plots;
    const { radius, height } = extent();
    this.size = radius;
    this.arrowScale = 0.6 * radius / PEAK.R;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    stage.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color('#f4f5f7');
    this.scene.add(new THREE.HemisphereLight('#ffffff', '#9aa3b0', 2.2));
    const sun = new THREE.DirectionalLight('#ffffff', 1.6);
    sun.position.set(1, -2, 3);
    this.scene.add(sun);
    this.camera = new THREE.PerspectiveCamera(40, 1, radius / 100, radius * 100);
    this.camera.up.set(0, 0, 1);
    this.target = new THREE.Vector3(0, 0, 0.45 * height);
    this.orbit = { azimuth: -1.1, elevation: 0.42, distance: 3.3 * Math.max(radius, 0.6 * height) };
    this.base = polygon(THREE, DATA.base_joints, '#aab2bf');
    this.platform = polygon(THREE, DATA.platform_joints, '#7f8da3');
    this.scene.add(this.base, this.platform);
    if (DATA.payload.mass > 0) this.platform.add(payload(THREE, radius));
    this.legs = makeLegs(THREE, this.scene, DATA.legs.radius);
    this.picks = this.legs.flatMap((p) => [p.cylinder, p.rod, p.collar, p.E, p.C]);
    this.labels = LEGS.map((leg) => {
      const label = document.createElement('div');
      label.className = 'label';
      label.style.color = LEG_COLOURS[leg];
      label.textContent = String(leg + 1);
      $('labels').append(label);
      return label;
    });
    this.hover = null;
    this.placed = [];
    this.listen();
    new ResizeObserver(() => this.resize()).observe(stage);
    this.resize();
  }

  resize() {
    const width = this.stage.clientWidth;
    const height = this.stage.clientHeight;
    this.renderer.setSize(width, height);
    this.camera.aspect = width / Math.max(height, 1);
    this.camera.updateProjectionMatrix();
    this.render();
  }

  update(frame) {
    const joints = jointsAt(frame);
    this.platform.position.set(...joints.p);
    const [w, x, y, z] = joints.q;
    this.platform.quaternion.set(x, y, z, w);
    this.placed = LEGS.map((leg) => updateLeg(this.THREE, this.legs[leg], leg, frame, joints, this.arrowScale));
    const flagged = A.flag[frame] !== 0;
    for (const outline of [this.platform.outline, this.base.outline]) outline.color.set(flagged ? FLAG_COLOUR : '#3a4150');
    this.render();
  }

  render() {
    const o = this.orbit;
    const c = Math.cos(o.elevation);
    this.camera.position.set(this.target.x + o.distance * c * Math.cos(o.azimuth),
      this.target.y + o.distance * c * Math.sin(o.azimuth), this.target.z + o.distance * Math.sin(o.elevation));
    this.camera.lookAt(this.target);
    this.renderer.render(this.scene, this.camera);
    this.placeLabels();
    this.showTip();
  }

  screen(point) {
    const v = new this.THREE.Vector3(...point).project(this.camera);
    return [(v.x + 1) / 2 * this.stage.clientWidth, (1 - v.y) / 2 * this.stage.clientHeight];
  }

  placeLabels() {
    this.placed.forEach(({ C, E }, leg) => {
      const mid = [0, 1, 2].map((j) => 0.45 * C[j] + 0.55 * E[j]);
      const [x, y] = this.screen(mid);
      this.labels[leg].style.left = `${x + 12}px`;
      this.labels[leg].style.top = `${y}px`;
    });
  }

  showTip() {
    const leg = state.pinned !== null ? state.pinned : this.hover;
    const tip = $('tip');
    if (leg === null || !this.placed[leg]) { tip.style.display = 'none'; return; }
    const { C, E, d } = this.placed[leg];
    tip.textContent = legText(leg, state.frame, d);
    const [x, y] = this.screen([0, 1, 2].map((j) => 0.5 * (C[j] + E[j])));
    tip.style.display = 'block';
    const left = Math.min(x + 18, this.stage.clientWidth - tip.offsetWidth - 4);
    tip.style.left = `${Math.max(4, left)}px`;
    tip.style.top = `${Math.min(Math.max(4, y - tip.offsetHeight / 2), this.stage.clientHeight - tip.offsetHeight - 4)}px`;
  }

  pick(event) {
    const box = this.renderer.domElement.getBoundingClientRect();
    const pointer = new this.THREE.Vector2((event.clientX - box.left) / box.width * 2 - 1,
      -(event.clientY - box.top) / box.height * 2 + 1);
    const ray = new this.THREE.Raycaster();
    ray.setFromCamera(pointer, this.camera);
    const hit = ray.intersectObjects(this.picks, false)[0];
    return hit ? hit.object.userData.leg : null;
  }

  select(leg) {
    state.pinned = leg;
    this.legs.forEach((parts, i) => {
      for (const mesh of [parts.cylinder, parts.rod]) mesh.material.emissive.set(i === leg ? '#333333' : '#000000');
    });
    this.plots.forEach((plot) => plot.select(leg));
    this.render();
  }

  listen() {
    const canvas = this.renderer.domElement;
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY, moved: 0 }; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener('pointermove', (e) => {
      if (drag) {
        const dx = e.clientX - drag.x; const dy = e.clientY - drag.y;
        drag.moved += Math.abs(dx) + Math.abs(dy);
        drag.x = e.clientX; drag.y = e.clientY;
        this.orbit.azimuth -= dx * 0.008;
        this.orbit.elevation = Math.min(1.55, Math.max(-1.55, this.orbit.elevation + dy * 0.008));
        this.render();
        return;
      }
      const leg = this.pick(e);
      if (leg !== this.hover) { this.hover = leg; this.render(); }
    });
    canvas.addEventListener('pointerup', (e) => {
      if (drag && drag.moved < 4) { const leg = this.pick(e); this.select(leg === state.pinned ? null : leg); }
      drag = null;
    });
    canvas.addEventListener('pointerleave', () => { if (this.hover !== null) { this.hover = null; this.render(); } });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.orbit.distance *= Math.exp(Math.max(-0.5, Math.min(0.5, e.deltaY * 0.001)));
      this.render();
    }, { passive: false });
  }
}

async function main() {
  setUpControls();
  setUpLegend();
  const plots = setUpPlots();
  setFrame(0);
  seekToHash();
  let THREE;
  try {
    THREE = await loadThree();
    const view = new View(THREE, $('stage'), plots);
    listeners.push((frame) => view.update(frame));
    if (DATA.focus) listeners.push((frame) => view.select(DATA.focus[frame]));
    view.update(state.frame);
    if (DATA.focus) view.select(DATA.focus[state.frame]);
  } catch (error) {
    $('nogl').style.display = 'block';
    $('nogl').textContent += ` (${error && error.message ? error.message : error})`;
  }
  document.body.dataset.ready = 'true';
}

main();
