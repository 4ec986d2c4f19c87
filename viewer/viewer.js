// viewer.js: the frepmilld browser viewer (docs/viewer.md). Lists jobs,
// opens one, shows its stock as Draco chunk meshes updated live from the
// job's server-sent events, the toolpath (rapids dashed, feeds solid), the
// program with the current line, the tool tip position, findings in red and
// a timeline that replays the job: the toolpath, and the stock as it was at
// that program time (the daemon's mesh history, GET .../chunks?at=T); for a
// finished job with a design, a colour mode by the deviation from it (gouge
// red, excess blue, green within tolerance, key in mm).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';

const $ = (id) => document.getElementById(id);
const BACKGROUND = 0x1b1f24;
const RAPID_COLOR = 0xe0b040;
const FEED_COLOR = 0x40c0ff;
const FINDING_COLOR = 0xff3030;

// ----------------------------------------------------------------- scene --

// Software WebGL (SwiftShader: headless browsers, VMs without a GPU) gets
// no multisampling and one pixel per CSS pixel: it rasterizes on the CPU.
function softwareGL() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
    const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : '';
    gl?.getExtension('WEBGL_lose_context')?.loseContext();
    return /swiftshader|llvmpipe|software/i.test(name);
  } catch (e) {
    return false;
  }
}
const software = softwareGL();
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: !software });
renderer.setPixelRatio(software ? 1 : Math.min(window.devicePixelRatio || 1, 2));
renderer.setClearColor(BACKGROUND, 1);
view.appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, 1, 0.1, 100000);
camera.up.set(0, 0, 1); // machine coordinates: Z up
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;

scene.add(new THREE.HemisphereLight(0xffffff, 0x404850, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.position.set(1, -2, 3);
scene.add(sun);
const fill = new THREE.DirectionalLight(0xffffff, 0.6);
fill.position.set(-2, 1, 1);
scene.add(fill);
const axes = new THREE.AxesHelper(10);
scene.add(axes);

const stockGroup = new THREE.Group();
const pathGroup = new THREE.Group();
const findingGroup = new THREE.Group();
// The finished stock in deviation colours (one mesh, GET .../deviation.drc),
// shown instead of the chunks in the deviation colour mode.
const deviationGroup = new THREE.Group();
deviationGroup.visible = false;
// The workpiece frame: on a machine whose rotary axes turn the table, the
// stock, its toolpath and findings turn with it during replay (placementAt:
// the daemon's placements);
// the tool marker stays in the machine frame.
const workpiece = new THREE.Group();
workpiece.matrixAutoUpdate = false;
workpiece.add(stockGroup, deviationGroup, pathGroup, findingGroup);
scene.add(workpiece);

const stockMaterial = new THREE.MeshStandardMaterial({
  color: 0xc8ccd2, metalness: 0.25, roughness: 0.55, side: THREE.DoubleSide,
});
const stockMaterialColored = stockMaterial.clone();
stockMaterialColored.vertexColors = true;
stockMaterialColored.color.set(0xffffff);

// The tool marker: a cone whose tip sits at the tool tip.
const marker = new THREE.Group();
{
  const cone = new THREE.Mesh(new THREE.ConeGeometry(2, 6, 24),
    new THREE.MeshStandardMaterial({ color: 0xff9a2e, emissive: 0x402000 }));
  cone.rotation.x = -Math.PI / 2; // cone points along -Z
  cone.position.z = 3;
  const shank = new THREE.Mesh(new THREE.CylinderGeometry(2, 2, 20, 24),
    new THREE.MeshStandardMaterial({ color: 0xb0b8c0, transparent: true, opacity: 0.35 }));
  shank.rotation.x = Math.PI / 2;
  shank.position.z = 16;
  marker.add(cone, shank);
  marker.visible = false;
  scene.add(marker);
}

function resize() {
  const w = view.clientWidth || 1, h = view.clientHeight || 1;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);

let bounds = null; // THREE.Box3 of what the view was framed on

function frame(box) {
  if (!box || box.isEmpty()) return;
  bounds = box.clone();
  const center = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3()).length() || 10;
  // An isometric-ish view from the front right, above.
  const dir = new THREE.Vector3(1, -1.35, 1.05).normalize();
  camera.position.copy(center).addScaledVector(dir, size * 1.65);
  camera.near = size / 100;
  camera.far = size * 20;
  camera.updateProjectionMatrix();
  controls.target.copy(center);
  controls.update();
  axes.scale.setScalar(Math.max(size / 12, 1) / 10);
  invalidate();
}

// Render on demand, and while chunks stream in at most every 400 ms (with
// software WebGL a frame of a large mesh costs the CPU that the downloads
// and the decoder need).
let dirty = true, lastRender = 0;
function invalidate() { dirty = true; }
function render() {
  resize();
  renderer.render(scene, camera);
  dirty = false;
  lastRender = performance.now();
}
controls.addEventListener('change', invalidate);
window.addEventListener('resize', invalidate);
function loop(now) {
  requestAnimationFrame(loop);
  tick();
  const wait = S.syncing ? 400 : 0;
  if (dirty && now - lastRender >= wait) render();
}

// ----------------------------------------------------------------- state --

const draco = new DRACOLoader();
draco.setDecoderPath('./node_modules/three/examples/jsm/libs/draco/');

const S = {
  jobId: null,
  job: null,            // last status JSON
  jobState: null,       // queued | running | done | failed | cancelled
  version: 0,           // stock version of the chunks shown
  chunks: new Map(),    // id -> {mesh, version, triangles}
  syncing: false,
  syncAgain: false,
  synced: false,        // the job has ended and the chunks shown match the daemon's
  timePlanned: false,   // the job's times are the controller's (status program_time_planned)
  shownAt: null,        // program time of the stock shown when replaying (null: the current stock)
  historyNote: '',      // why the stock of an earlier time cannot be shown
  events: null,         // EventSource
  toolpath: null,       // {motions, points, program, ...}
  toolNames: {},        // tool number -> its description in the job's table (status "tools")
  programLines: [],
  line: 0,
  findings: [],
  live: true,           // follow the job (else: replay at S.replayT)
  playing: false,
  replayT: 0,
  totalT: 0,
  errors: [],
  generation: 0,        // bumped on each open: late answers of older jobs are dropped
  colorMode: 'tool',    // the mode chosen: tool | deviation (kept from job to job)
  deviation: null,      // the job's deviation key (GET .../deviation), null: none
  deviationMesh: null,  // its mesh once loaded
  deviationLoading: null,
};

async function getJSON(url) {
  const r = await fetch(url, { cache: 'no-store' });
  if (!r.ok) {
    let msg = `${r.status}`;
    try { msg = (await r.json()).error.message; } catch (e) { /* not JSON */ }
    const e = new Error(`${url}: ${msg}`);
    e.status = r.status;
    e.detail = msg;
    throw e;
  }
  return r.json();
}

function fmt(v, d = 3) { return typeof v === 'number' && isFinite(v) ? v.toFixed(d) : '-'; }

// ------------------------------------------------------------------ jobs --

async function refreshJobs() {
  try {
    const list = await getJSON('/v1/jobs');
    $('conn').textContent = 'connected';
    const ul = $('jobs');
    ul.textContent = '';
    for (const j of list.jobs) {
      const li = document.createElement('li');
      li.dataset.id = j.id;
      if (j.id === S.jobId) li.className = 'open';
      const name = document.createElement('span');
      name.textContent = `${j.name || 'job'} ${j.id}`;
      const st = document.createElement('span');
      st.className = `state ${j.state}`;
      st.textContent = j.state === 'running' ? `${Math.round(100 * j.progress)}%` : j.state;
      li.append(name, st);
      li.addEventListener('click', () => { location.hash = `job=${j.id}`; });
      ul.appendChild(li);
    }
    if (!S.jobId && list.jobs.length && !location.hash.includes('job=')) {
      location.hash = `job=${list.jobs[list.jobs.length - 1].id}`;
    }
  } catch (e) {
    $('conn').textContent = 'no connection';
  }
}

function jobFromHash() {
  const m = /job=([0-9A-Za-z_-]+)/.exec(location.hash);
  return m ? m[1] : null;
}

window.addEventListener('hashchange', () => {
  const id = jobFromHash();
  if (id && id !== S.jobId) openJob(id);
});

// ---------------------------------------------------------------- chunks --

function removeChunk(id) {
  const c = S.chunks.get(id);
  if (!c) return;
  stockGroup.remove(c.mesh);
  c.mesh.geometry.dispose();
  S.chunks.delete(id);
  invalidate();
}

function decode(buffer) {
  return new Promise((resolve, reject) => draco.parse(buffer, resolve, reject));
}

// byVersion: fetch the version the list named (a replay's earlier mesh),
// else the chunk's current mesh.
async function loadChunk(gen, info, byVersion) {
  if (!info.triangles) {
    removeChunk(info.id);
    return;
  }
  const v = byVersion ? `?v=${info.version}` : '';
  const r = await fetch(`/v1/jobs/${S.jobId}/chunks/${info.id}.drc${v}`, { cache: 'no-store' });
  if (gen !== S.generation) return;
  if (!r.ok) throw new Error(`chunk ${info.id}: ${r.status}`);
  const buf = await r.arrayBuffer();
  if (gen !== S.generation) return;
  if (!buf.byteLength) { removeChunk(info.id); return; }
  const bytes = buf.byteLength; // (the decoder's worker takes the buffer)
  const geometry = await decode(buf);
  if (gen !== S.generation) { geometry.dispose(); return; }
  if (!geometry.getAttribute('normal')) geometry.computeVertexNormals();
  const material = geometry.getAttribute('color') ? stockMaterialColored : stockMaterial;
  const old = S.chunks.get(info.id);
  const mesh = new THREE.Mesh(geometry, material);
  mesh.name = info.id;
  stockGroup.add(mesh);
  if (old) { stockGroup.remove(old.mesh); old.mesh.geometry.dispose(); }
  S.chunks.set(info.id, { mesh, version: info.version, triangles: info.triangles, bytes });
  invalidate();
}

// Frame once on the stock and the toolpath together, when the stock first arrives.
function frameOnStock() {
  if (S.framed || !stockGroup.children.length) return;
  const box = new THREE.Box3().setFromObject(stockGroup);
  if (pathGroup.children.length) box.union(new THREE.Box3().setFromObject(pathGroup));
  frame(box);
  S.framed = true;
}

// A done job opened: its whole stock as one mesh (GET .../stock.drc, meshed
// once by the daemon with adaptivity: far fewer triangles than its chunks,
// one request instead of hundreds; docs/viewer.md). It is kept in S.chunks
// under the name WHOLE, so a replay's chunk list (which never names it)
// replaces it. False: the daemon has none (an older daemon, no stock).
const WHOLE = 'whole';
async function loadWhole(gen, version) {
  const r = await fetch(`/v1/jobs/${S.jobId}/stock.drc`, { cache: 'no-store' });
  if (gen !== S.generation) return true;
  if (!r.ok) return false;
  const buf = await r.arrayBuffer();
  if (gen !== S.generation) return true;
  const bytes = buf.byteLength; // (the decoder's worker takes the buffer)
  const geometry = await decode(buf);
  if (gen !== S.generation) { geometry.dispose(); return true; }
  if (!S.live) { geometry.dispose(); return true; } // replaying meanwhile: its chunks show
  if (!geometry.getAttribute('normal')) geometry.computeVertexNormals();
  const material = geometry.getAttribute('color') ? stockMaterialColored : stockMaterial;
  for (const id of [...S.chunks.keys()]) removeChunk(id);
  const mesh = new THREE.Mesh(geometry, material);
  mesh.name = WHOLE;
  stockGroup.add(mesh);
  const tris = (geometry.index ? geometry.index.count : geometry.getAttribute('position').count) / 3;
  S.chunks.set(WHOLE, { mesh, version, triangles: tris, bytes });
  S.version = version;
  S.shownAt = null;
  S.historyNote = '';
  frameOnStock();
  updateMeshReadout();
  invalidate();
  S.synced = true;
  return true;
}

// Bring the chunks shown up to date. Following the job (S.live): those
// changed since the version shown, or (full) every chunk whose version
// differs from the one shown. Replaying: the chunks as they were at program
// time S.replayT, from the daemon's mesh history.
async function syncChunks(full = false) {
  if (!S.jobId) return;
  if (S.syncing) { S.syncAgain = full ? 'full' : (S.syncAgain || true); return; }
  S.syncing = true;
  const gen = S.generation;
  const at = S.live ? null : S.replayT;
  // Coming back from an earlier time, every chunk is compared.
  const whole = full || at !== null || S.shownAt !== null;
  try {
    let list;
    try {
      list = await getJSON(at === null ? `/v1/jobs/${S.jobId}/chunks?since=${whole ? 0 : S.version}`
        : `/v1/jobs/${S.jobId}/chunks?at=${at}`);
    } catch (e) {
      if (at === null || (e.status !== 410 && e.status !== 404)) throw e;
      // That time's meshes are gone (the daemon's history bound) or not made yet.
      if (gen === S.generation) { S.shownAt = at; S.historyNote = e.detail || String(e); updateMeshReadout(); }
      return;
    }
    if (gen !== S.generation) return;
    const todo = list.chunks.filter((c) => {
      const have = S.chunks.get(c.id);
      return !whole || !have || have.version !== c.version || !c.triangles;
    });
    if (whole) {
      const listed = new Set(list.chunks.map((c) => c.id));
      for (const id of [...S.chunks.keys()]) if (!listed.has(id)) removeChunk(id);
    }
    // A few requests at a time.
    let next = 0;
    const worker = async () => { while (next < todo.length) await loadChunk(gen, todo[next++], at !== null); };
    await Promise.all([worker(), worker(), worker(), worker()]);
    if (gen !== S.generation) return;
    if (at === null) S.version = S.shownAt !== null ? list.version : Math.max(S.version, list.version);
    S.shownAt = at;
    S.historyNote = '';
    frameOnStock();
    updateMeshReadout();
  } catch (e) {
    S.errors.push(String(e));
    console.error(e);
  } finally {
    if (gen === S.generation) {
      S.syncing = false;
      const again = S.syncAgain;
      S.syncAgain = false;
      if (again) syncChunks(again === 'full');
      else if (!S.live && S.shownAt !== S.replayT) syncChunks();
      else if (S.live && S.shownAt !== null) syncChunks(true);
      else if (full && isEnded()) S.synced = true;
    }
  }
}

function triangleCount() {
  let n = 0;
  for (const c of S.chunks.values()) {
    const g = c.mesh.geometry;
    n += (g.index ? g.index.count : g.getAttribute('position').count) / 3;
  }
  return n;
}

function meshBytes() {
  let n = 0;
  for (const c of S.chunks.values()) n += c.bytes || 0;
  return n;
}

function updateMeshReadout() {
  const when = S.shownAt === null ? `v${S.version}` : `at ${fmt(S.shownAt, 1)} s`;
  const parts = S.chunks.has(WHOLE) ? 'whole stock' : `${S.chunks.size} chunks`;
  $('mesh').textContent = `${triangleCount().toLocaleString('en')} triangles, ${parts}, ` +
    `${(meshBytes() / 1e6).toFixed(2)} MB, ${when}` + (S.historyNote ? ` (${S.historyNote})` : '');
}

function isEnded() {
  return S.jobState === 'done' || S.jobState === 'failed' || S.jobState === 'cancelled';
}

// -------------------------------------------------------------- toolpath --

function buildToolpath(tp) {
  for (const o of [...pathGroup.children]) { pathGroup.remove(o); o.geometry.dispose(); }
  const P = tp.points;
  const rapid = [], feed = [], rapidT = [], feedT = [];
  for (const m of tp.motions) {
    const [kind, , t0, t1, , first, count] = m;
    if (kind === 4 || count < 2) continue;
    const dst = kind === 0 ? rapid : feed;
    const dstT = kind === 0 ? rapidT : feedT;
    for (let i = 0; i + 1 < count; i++) {
      const a = 3 * (first + i), b = 3 * (first + i + 1);
      dst.push(P[a], P[a + 1], P[a + 2], P[b], P[b + 1], P[b + 2]);
      dstT.push(t0 + (t1 - t0) * (i + 1) / (count - 1)); // time the segment ends
    }
  }
  const make = (pos, material) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    const l = new THREE.LineSegments(g, material);
    l.computeLineDistances();
    return l;
  };
  const dim = (c) => ({ color: c, transparent: true, opacity: 0.22, depthWrite: false });
  const lines = {
    rapidAll: make(rapid, new THREE.LineDashedMaterial({ ...dim(RAPID_COLOR), dashSize: 2, gapSize: 1.5 })),
    feedAll: make(feed, new THREE.LineBasicMaterial(dim(FEED_COLOR))),
    rapidDone: make(rapid, new THREE.LineDashedMaterial({ color: RAPID_COLOR, dashSize: 2, gapSize: 1.5 })),
    feedDone: make(feed, new THREE.LineBasicMaterial({ color: FEED_COLOR })),
  };
  pathGroup.add(...Object.values(lines));
  invalidate();
  S.pathLines = { ...lines, rapidT, feedT };
  S.totalT = tp.motions.length ? tp.motions[tp.motions.length - 1][3] : 0;
  if (!bounds && P.length) {
    const box = new THREE.Box3();
    box.setFromBufferAttribute(new THREE.Float32BufferAttribute(P, 3));
    frame(box);
  }
}

// Count of segments ending at or before t (times are non-decreasing).
function upTo(times, t) {
  let lo = 0, hi = times.length;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (times[mid] <= t + 1e-9) lo = mid + 1; else hi = mid; }
  return lo;
}

function showPathUpTo(t) {
  const L = S.pathLines;
  if (!L) return;
  L.rapidDone.geometry.setDrawRange(0, 2 * upTo(L.rapidT, t));
  L.feedDone.geometry.setDrawRange(0, 2 * upTo(L.feedT, t));
  invalidate();
}

// Where the table puts the workpiece at point k of the toolpath: the daemon's
// placement there (the toolpath document's "placements", 12 numbers a point:
// x_machine = R x + t, R row-major, from fm_machine_table_transform), as a
// matrix; identity without a table.
function placementAt(k) {
  const M = new THREE.Matrix4();
  const Q = S.toolpath && S.toolpath.placements;
  if (!Q || 12 * k + 11 >= Q.length) return M;
  const q = Q.slice(12 * k, 12 * k + 12);
  M.set(q[0], q[1], q[2], q[9], q[3], q[4], q[5], q[10], q[6], q[7], q[8], q[11], 0, 0, 0, 1);
  return M;
}

// Between two points of a motion (at most 5 degrees of any joint apart) the
// table turns on: the turn between their placements taken a fraction r of
// the way (a spherical interpolation, exact for a turn about one axis), the
// translation in proportion.
function placementBetween(ka, kb, r) {
  const A = placementAt(ka);
  if (kb === ka || r <= 0) return A;
  const B = placementAt(kb);
  const pa = new THREE.Vector3(), qa = new THREE.Quaternion(), sa = new THREE.Vector3();
  const pb = new THREE.Vector3(), qb = new THREE.Quaternion(), sb = new THREE.Vector3();
  A.decompose(pa, qa, sa);
  B.decompose(pb, qb, sb);
  return new THREE.Matrix4().compose(pa.lerp(pb, r), qa.slerp(qb, r), new THREE.Vector3(1, 1, 1));
}

function placeWorkpiece(placement, joints) {
  workpiece.matrix.copy(placement || new THREE.Matrix4());
  workpiece.matrixWorldNeedsUpdate = true;
  S.joints = joints || null;
}

// The motion at program time t, the tool tip there (workpiece frame), the
// joints (degrees, when the motion carries them: they move linearly in time)
// and the table's placement of the workpiece there (null without a table).
function poseAt(t) {
  const tp = S.toolpath;
  if (!tp || !tp.motions.length) return null;
  const M = tp.motions;
  let lo = 0, hi = M.length - 1;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (M[mid][3] < t) lo = mid + 1; else hi = mid; }
  const [, line, t0, t1, tool, first, count] = M[lo];
  const P = tp.points;
  let f = t1 > t0 ? (t - t0) / (t1 - t0) : 1;
  f = Math.min(Math.max(f, 0), 1);
  const x = f * (count - 1), i = Math.min(Math.floor(x), Math.max(count - 2, 0)), r = count > 1 ? x - i : 0;
  const a = 3 * (first + i), b = 3 * (first + Math.min(i + 1, count - 1));
  const pos = [0, 1, 2].map((k) => P[a + k] + (P[b + k] - P[a + k]) * r);
  const m = M[lo];
  const joints = m.length >= 13 ? [0, 1, 2].map((k) => m[7 + k] + (m[10 + k] - m[7 + k]) * f) : null;
  const placement = tp.placements ? placementBetween(first + i, first + Math.min(i + 1, count - 1), r) : null;
  return { line, tool, pos, joints, placement };
}

// --------------------------------------------------------------- program --

function renderProgram(line) {
  const box = $('program');
  const lines = S.programLines;
  if (!lines.length) {
    box.textContent = line ? `line ${line} (no program text)` : '';
    return;
  }
  // Only a window around the current line is in the page, so a program of
  // a million lines costs nothing.
  const from = Math.max(1, line - 60), to = Math.min(lines.length, Math.max(line, 1) + 60);
  const findingLines = new Set(S.findings.map((f) => f.line));
  box.textContent = '';
  let current = null;
  for (let n = from; n <= to; n++) {
    const div = document.createElement('div');
    const ln = document.createElement('span');
    ln.className = 'ln';
    ln.textContent = n;
    div.append(ln, document.createTextNode(lines[n - 1]));
    if (n === line) { div.className = 'current'; current = div; }
    if (findingLines.has(n)) div.classList.add('finding');
    box.appendChild(div);
  }
  if (current) box.scrollTop = current.offsetTop - box.clientHeight / 2;
}

function setLine(line) {
  if (line === S.line) return;
  S.line = line;
  $('line').textContent = line > 0 ? line : '-';
  renderProgram(line);
}

// -------------------------------------------------------------- findings --

function setFindings(list) {
  S.findings = list || [];
  for (const o of [...findingGroup.children]) { findingGroup.remove(o); o.geometry.dispose(); }
  const ol = $('findings');
  ol.textContent = '';
  const mat = new THREE.MeshBasicMaterial({ color: FINDING_COLOR });
  const r = bounds ? Math.max(bounds.getSize(new THREE.Vector3()).length() / 150, 0.5) : 1;
  for (const f of S.findings) {
    const at = f.contact || f.position;
    if (Array.isArray(at)) {
      const s = new THREE.Mesh(new THREE.SphereGeometry(r, 16, 12), mat);
      s.position.set(at[0], at[1], at[2]);
      findingGroup.add(s);
    }
    const li = document.createElement('li');
    li.textContent = `${f.severity || ''} ${f.kind || 'finding'} line ${f.line}` +
      (f.part ? ` (${f.part})` : '') + (typeof f.penetration_mm === 'number' ? ` ${fmt(f.penetration_mm, 2)} mm` : '');
    li.addEventListener('click', () => {
      if (typeof f.time_s === 'number') { S.live = false; S.playing = false; S.replayT = f.time_s; applyReplay(); }
    });
    ol.appendChild(li);
  }
  $('finding-count').textContent = S.findings.length;
  invalidate();
  renderProgram(S.line);
}

// ------------------------------------------------------------- deviation --

// The key and the mesh come from files the daemon writes when a job with a
// design is done (docs/api.md): the page asks once the job has ended.
async function loadDeviationKey(gen) {
  if (!S.job || !S.job.design) return;
  let key = null;
  try {
    const r = await fetch(`/v1/jobs/${S.jobId}/deviation`, { cache: 'no-store' });
    if (r.ok) key = await r.json();
  } catch (e) {
    S.errors.push(String(e));
  }
  if (gen !== S.generation) return;
  S.deviation = key;
  $('color-mode').querySelector('option[value="deviation"]').disabled = !key;
  applyColorMode();
}

async function loadDeviationMesh(gen) {
  const r = await fetch(`/v1/jobs/${S.jobId}/deviation.drc`, { cache: 'no-store' });
  if (!r.ok) throw new Error(`deviation mesh: ${r.status}`);
  const buf = await r.arrayBuffer();
  if (gen !== S.generation) return;
  const geometry = await decode(buf);
  if (gen !== S.generation) { geometry.dispose(); return; }
  if (!geometry.getAttribute('normal')) geometry.computeVertexNormals();
  const mesh = new THREE.Mesh(geometry, stockMaterialColored);
  mesh.name = 'deviation';
  deviationGroup.add(mesh);
  S.deviationMesh = mesh;
  invalidate();
}

function removeDeviation() {
  for (const o of [...deviationGroup.children]) { deviationGroup.remove(o); o.geometry.dispose(); }
  S.deviation = null;
  S.deviationMesh = null;
  S.deviationLoading = null;
  $('color-mode').querySelector('option[value="deviation"]').disabled = true;
}

function showDeviationKeys(key) {
  const title = document.createElement('span');
  title.className = 'title';
  title.textContent = 'deviation, mm';
  const swatches = key.legend.map(({ label, color }) => {
    const k = document.createElement('span');
    k.className = 'tool-key';
    k.style.setProperty('--swatch', color);
    k.textContent = label;
    return k;
  });
  $('deviation-keys').replaceChildren(title, ...swatches);
  $('deviation-keys').title = `green within ±${fmt(key.tolerance_mm, 3)} mm of the design, ` +
    `red: gouge (design material removed), blue: excess (material left); ` +
    `max gouge ${fmt(key.max_gouge_mm, 3)} mm, max excess ${fmt(key.max_excess_mm, 3)} mm`;
}

// Show the colours of the mode chosen when the job has them, else by tool.
function applyColorMode() {
  const dev = S.colorMode === 'deviation' && S.deviation !== null;
  $('color-mode').value = dev ? 'deviation' : 'tool';
  $('tool-keys').hidden = dev;
  $('deviation-keys').hidden = !dev;
  if (dev) {
    showDeviationKeys(S.deviation);
    if (!S.deviationMesh && !S.deviationLoading) {
      const gen = S.generation;
      S.deviationLoading = loadDeviationMesh(gen).catch((e) => {
        if (gen === S.generation) { S.errors.push(String(e)); S.deviationLoading = null; }
      });
    }
  }
  const shown = $('show-stock').checked;
  stockGroup.visible = shown && !dev;
  deviationGroup.visible = shown && dev;
  invalidate();
}

$('color-mode').addEventListener('change', (e) => { S.colorMode = e.target.value; applyColorMode(); });

// ---------------------------------------------------------------- status --

// The legend's swatches: the stock's colour for each tool of the job, each
// named (its title) as the job's tool table or library describes it.
function showToolKeys(list) {
  const box = $('tool-keys');
  box.replaceChildren(...list.map(({ tool, color }) => {
    const k = document.createElement('span');
    k.className = 'tool-key';
    k.style.setProperty('--swatch', color);
    k.textContent = `T${tool}`;
    if (S.toolNames[tool]) k.title = S.toolNames[tool];
    return k;
  }));
}

// The tool in the readout: its number and, when the table names it, its
// description ("T1 6 mm flat end mill, 2 flutes").
function toolLabel(tool) {
  const name = S.toolNames[tool];
  return name ? `T${tool} ${name}` : `T${tool}`;
}

function showStatus(st) {
  S.job = { ...(S.job || {}), ...st };
  const j = S.job;
  if (j.state) S.jobState = j.state;
  $('job-state').textContent = S.jobState || '-';
  $('job-state').className = `state ${S.jobState}`;
  const p = typeof j.progress === 'number' ? j.progress : 0;
  $('job-progress').value = p;
  $('job-percent').textContent = `${Math.round(p * 100)}%`;
  $('removed').textContent = j.removed_volume_mm3 != null ? `${fmt(j.removed_volume_mm3, 1)} mm³` : '-';
  $('stock').textContent = j.stock_volume_mm3 != null ? `${fmt(j.stock_volume_mm3, 1)} mm³` : '-';
  if (typeof st.program_time_planned === 'boolean') S.timePlanned = st.program_time_planned;
  if (typeof st.program_time_planned === 'boolean') S.timePlanned = st.program_time_planned;
  if (Array.isArray(st.tools))
    S.toolNames = Object.fromEntries(st.tools.map(({ tool, description }) => [tool, description]));
  if (Array.isArray(st.tool_colors)) showToolKeys(st.tool_colors);
  const err = $('error');
  if (j.error) {
    err.hidden = false;
    err.textContent = `${j.error.message || j.error.code}` + (j.error.line ? ` (line ${j.error.line})` : '');
  } else err.hidden = true;
  if (S.live) {
    // Program time: the status has it, progress events have the fraction.
    const t = typeof st.program_time_s === 'number' ? st.program_time_s
      : typeof st.progress === 'number' ? st.progress * S.totalT : null;
    if (t !== null) {
      showPathUpTo(t);
      setScrub(t);
      // the table where the program has turned it by now
      const pose = poseAt(t);
      if (pose && pose.placement) placeWorkpiece(pose.placement, pose.joints);
    }
    if (Array.isArray(j.position)) showPosition(j.position, j.tool);
    if (j.line) setLine(j.line);
  }
}

// pos: the tip in the workpiece frame (the readout); the marker shows the
// tool where the machine holds it (the workpiece's placement applied).
function showPosition(pos, tool) {
  $('pos-x').textContent = fmt(pos[0]);
  $('pos-y').textContent = fmt(pos[1]);
  $('pos-z').textContent = fmt(pos[2]);
  if (tool != null) $('tool').textContent = toolLabel(tool);
  marker.position.set(...pos).applyMatrix4(workpiece.matrix);
  marker.visible = true;
  invalidate();
}

// -------------------------------------------------------------- timeline --

function setScrub(t) {
  const T = S.totalT || 0;
  $('scrub').value = T > 0 ? Math.round(1000 * Math.min(t / T, 1)) : 1000;
  // the controller's time when the machine's dynamics planned it (the
  // toolpath's times and the status' program_time_s are then both planned)
  $('time').textContent = `${fmt(t, 1)} / ${fmt(T, 1)} s` + (S.timePlanned ? ' planned' : '');
}

function applyReplay() {
  const t = Math.min(Math.max(S.replayT, 0), S.totalT);
  showPathUpTo(t);
  setScrub(t);
  const pose = poseAt(t);
  if (pose) {
    placeWorkpiece(pose.placement, pose.joints);
    showPosition(pose.pos, pose.tool);
    setLine(pose.line);
  }
  // the stock as it was then
  if (!S.live && S.shownAt !== S.replayT) syncChunks();
  $('live').classList.toggle('on', S.live);
  $('play').innerHTML = S.playing ? '&#10074;&#10074;' : '&#9654;';
}

let lastTick = performance.now();
function tick() {
  const now = performance.now();
  const dt = (now - lastTick) / 1000;
  lastTick = now;
  if (!S.playing || S.live) return;
  const sp = $('speed').value;
  const rate = sp === 'auto' ? Math.max(S.totalT, 1e-6) / 20 : Number(sp);
  S.replayT += dt * rate;
  if (S.replayT >= S.totalT) { S.replayT = S.totalT; S.playing = false; }
  applyReplay();
}

$('scrub').addEventListener('input', () => {
  S.live = false;
  S.replayT = (Number($('scrub').value) / 1000) * S.totalT;
  applyReplay();
});
$('play').addEventListener('click', () => {
  if (S.live || S.replayT >= S.totalT) { S.replayT = S.live && !isEnded() ? S.replayT : 0; }
  S.live = false;
  S.playing = !S.playing;
  applyReplay();
});
$('live').addEventListener('click', () => {
  S.live = true;
  S.playing = false;
  $('live').classList.add('on');
  if (S.job) showStatus({ progress: S.job.progress });
  if (isEnded()) { showPathUpTo(Infinity); setScrub(S.totalT); }
  syncChunks(true); // back to the current stock
});
$('show-stock').addEventListener('change', () => applyColorMode());
$('show-path').addEventListener('change', (e) => { pathGroup.visible = e.target.checked; invalidate(); });
$('reset-view').addEventListener('click', () => {
  frame(stockGroup.children.length ? new THREE.Box3().setFromObject(stockGroup) : bounds);
});

// ------------------------------------------------------------------ open --

function closeJob() {
  if (S.events) { S.events.close(); S.events = null; }
  for (const id of [...S.chunks.keys()]) removeChunk(id);
  for (const o of [...pathGroup.children]) { pathGroup.remove(o); o.geometry.dispose(); }
  S.pathLines = null;
  setFindings([]);
  removeDeviation();
  applyColorMode();
  marker.visible = false;
  bounds = null;
  Object.assign(S, {
    job: null, jobState: null, version: 0, syncing: false, syncAgain: false, synced: false,
    shownAt: null, historyNote: '', timePlanned: false,
    toolpath: null, programLines: [], line: 0, live: true, playing: false, replayT: 0, totalT: 0,
    framed: false, toolNames: {},
  });
}

async function openJob(id) {
  closeJob();
  S.generation++;
  const gen = S.generation;
  S.jobId = id;
  api.jobId = id;
  $('job').hidden = false;
  for (const li of $('jobs').children) li.classList.toggle('open', li.dataset.id === id);
  let st;
  try {
    st = await getJSON(`/v1/jobs/${id}`);
  } catch (e) {
    S.errors.push(String(e));
    $('error').hidden = false;
    $('error').textContent = String(e.message || e);
    return;
  }
  if (gen !== S.generation) return;
  $('job-name').textContent = st.name ? `${st.name} ${id}` : id;
  S.jobState = st.state;
  // The toolpath and program first: it frames the view and sets the timeline.
  try {
    const tp = await getJSON(`/v1/jobs/${id}/toolpath`);
    if (gen !== S.generation) return;
    S.toolpath = tp;
    S.programLines = typeof tp.program === 'string' ? tp.program.split('\n') : [];
    buildToolpath(tp);
  } catch (e) {
    console.warn('no toolpath:', e);
  }
  showStatus(st);
  setFindings(st.findings);
  renderProgram(st.line || 0);
  if (isEnded()) {
    showPathUpTo(Infinity);
    setScrub(S.totalT);
    loadDeviationKey(gen);
  }
  // Live updates: events first, so no change between the listing and the
  // stream is missed (a chunk listed twice is merely fetched twice).
  if (!isEnded()) listen(id, gen);
  // Done: the whole stock in one request; else (or without one) the chunks.
  // (?chunks: always the chunks, to compare.)
  if (st.state === 'done' && !new URLSearchParams(location.search).has('chunks')) {
    try {
      if (await loadWhole(gen, st.mesh_version || 0)) return;
    } catch (e) {
      console.warn('no whole stock mesh:', e);
    }
    if (gen !== S.generation) return;
  }
  await syncChunks(true);
}

function listen(id, gen) {
  const es = new EventSource(`/v1/jobs/${id}/events`);
  S.events = es;
  const data = (e) => { try { return JSON.parse(e.data); } catch (x) { return {}; } };
  es.addEventListener('state', (e) => { if (gen === S.generation) showStatus(data(e)); });
  es.addEventListener('progress', (e) => { if (gen === S.generation) showStatus(data(e)); });
  es.addEventListener('block', (e) => {
    if (gen !== S.generation) return;
    const d = data(e);
    if (S.live && d.line) setLine(d.line);
  });
  // (replaying an earlier time, the stock shown stays that time's)
  es.addEventListener('chunks', () => { if (gen === S.generation && S.live) syncChunks(false); });
  es.addEventListener('finding', (e) => {
    if (gen === S.generation) setFindings([...S.findings, data(e)]);
  });
  es.addEventListener('end', async () => {
    es.close();
    if (gen !== S.generation) return;
    S.events = null;
    try {
      const st = await getJSON(`/v1/jobs/${id}`);
      if (gen !== S.generation) return;
      // A toolpath fetched before the job had read its program has the
      // feed-only times; the job's kept motions have the planned ones.
      if (st.program_time_planned && Math.abs(S.totalT - st.program_time_total_s) > 1e-3) {
        const tp = await getJSON(`/v1/jobs/${id}/toolpath`);
        if (gen !== S.generation) return;
        S.toolpath = tp;
        buildToolpath(tp);
      }
      showStatus(st);
      setFindings(st.findings);
    } catch (e) {
      S.errors.push(String(e));
      S.jobState = 'deleted';
    }
    if (S.live) { showPathUpTo(Infinity); setScrub(S.totalT); }
    loadDeviationKey(gen);
    // The last publication: compare every chunk with the daemon's list.
    syncChunks(true);
  });
  es.onerror = () => {
    // EventSource reconnects by itself (with Last-Event-ID); nothing to do.
  };
}

// ------------------------------------------------------------- test hook --

// Distinct vertex colours of the stock meshes as sRGB hex ("none" for a
// mesh without colours); the Draco loader turned them into linear values.
function vertexColors() {
  const seen = new Set();
  const c = new THREE.Color();
  for (const { mesh } of S.chunks.values()) {
    const a = mesh.geometry.getAttribute('color');
    if (!a) { seen.add('none'); continue; }
    for (let i = 0; i < a.count; i++) seen.add(c.setRGB(a.getX(i), a.getY(i), a.getZ(i)).getHexString());
  }
  return [...seen].sort();
}

// The deviation mesh shown: positions (mm, workpiece frame) and sRGB
// colours (0..255), flat arrays; null until it is loaded.
function deviationVertices() {
  if (!S.deviationMesh) return null;
  const g = S.deviationMesh.geometry;
  const p = g.getAttribute('position'), a = g.getAttribute('color');
  const c = new THREE.Color();
  const positions = [], colors = [];
  for (let i = 0; i < p.count; i++) {
    positions.push(p.getX(i), p.getY(i), p.getZ(i));
    if (a) {
      c.setRGB(a.getX(i), a.getY(i), a.getZ(i)).getRGB(c, THREE.SRGBColorSpace);
      colors.push(Math.round(255 * c.r), Math.round(255 * c.g), Math.round(255 * c.b));
    }
  }
  return { positions, colors };
}

const api = {
  jobId: null,
  state: S,
  triangleCount,
  vertexColors,
  deviationVertices,
  // The colour mode: 'tool' or 'deviation' (shown once the job's deviation is there).
  setColorMode: (mode) => { S.colorMode = mode; applyColorMode(); },
  deviationShown: () => deviationGroup.visible && S.deviationMesh !== null,
  // The workpiece's placement on the machine now (column-major 4x4).
  workpieceMatrix: () => workpiece.matrix.toArray(),
  chunkCount: () => S.chunks.size,
  // The whole stock's mesh is shown (a done job opened), not its chunks.
  wholeShown: () => S.chunks.has(WHOLE),
  // Bounding box of the stock shown, workpiece frame: [xmin, ymin, zmin, xmax, ymax, zmax].
  stockBox: () => {
    const b = new THREE.Box3();
    for (const { mesh } of S.chunks.values()) {
      mesh.geometry.computeBoundingBox();
      b.union(mesh.geometry.boundingBox);
    }
    return [...b.min.toArray(), ...b.max.toArray()];
  },
  open: (id) => { location.hash = `job=${id}`; },
  // Ended and the chunks shown match the daemon's list.
  idle: () => S.synced && !S.syncing,
  // Replaying: the program time whose stock is shown, once it is the
  // timeline's (null while it is still being fetched or when following).
  stockShownAt: () => (!S.live && !S.syncing && S.shownAt === S.replayT ? S.shownAt : null),
  render,
  software,
};
window.frepmillViewer = api;

resize();
frame(new THREE.Box3(new THREE.Vector3(0, 0, -30), new THREE.Vector3(100, 60, 0)));
bounds = null;
requestAnimationFrame(loop);
refreshJobs().then(() => { const id = jobFromHash(); if (id) openJob(id); });
setInterval(refreshJobs, 3000);
