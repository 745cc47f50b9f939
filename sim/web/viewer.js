// The viewer of a run's output folder (`twin view`): the world extruded from world.json, the
// true, odometry and estimated paths, the scans placed at the estimate, the robot replayed scan
// by scan, and the 3D model (model.ply) when the run has one. Navigation as in the thesis (§4.5,
// App. D.2): a virtual robot carries the camera 55 cm above the floor; arrows move and turn it,
// a/d pan and w/s tilt its head, p/o perspective/orthographic, x points, c edges, f fill. Frames
// follow REP-103: metres, x forward, y left, z up.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
const $ = (id) => document.getElementById(id);
const deg = Math.PI / 180;

// The thesis's steps (App. D.2; model units of 0.1 m).
export const STEP = {
  move: 0.057125, // m per arrow press
  turn: 2.34987 * deg, // per arrow press
  pan: 21.774 * deg, // a / d
  tilt: 3.409 * deg, // w / s, limited to ±90°
  eye: 0.55, // camera height, m
  fov: 80, // perspective, degrees
  ortho: 10, // orthographic half-height, m (±100 units)
};

const COLOURS = {
  matte: 0xd0d0d0, black: 0x303030, glass: 0x8ec9f0, metal: 0xb3a6c9,
  truth: 0x1a9850, odometry: 0xd73027, estimate: 0x6a3d9a, scans: 0x1f3b73, current: 0xe0115f,
  robot: 0xf08a24, model: 0xd9d4c7, sonar: 0x9b59b6,
};

const messages = [];
function note(text) {
  messages.push(text);
  $('messages').innerHTML = messages.map((m) => `<div>${m}</div>`).join('');
}

async function fetchText(name, required) {
  const r = await fetch(`/run/${name}`);
  if (!r.ok) {
    if (required) note(`${name} is missing: ${await r.text()}`);
    return null;
  }
  return r.text();
}

function parseTum(text) {
  if (!text) return [];
  const poses = [];
  for (const line of text.split('\n')) {
    if (!line || line.startsWith('#')) continue;
    const v = line.trim().split(/\s+/).map(Number);
    if (v.length < 8 || v.some((x) => !Number.isFinite(x))) continue;
    poses.push({ t: v[0], x: v[1], y: v[2], theta: 2 * Math.atan2(v[6], v[7]) });
  }
  return poses;
}

// Pose algebra in the plane.
const compose = (a, b) => ({
  x: a.x + Math.cos(a.theta) * b.x - Math.sin(a.theta) * b.y,
  y: a.y + Math.sin(a.theta) * b.x + Math.cos(a.theta) * b.y,
  theta: a.theta + b.theta,
});
const relative = (a, b) => {
  const dx = b.x - a.x, dy = b.y - a.y, c = Math.cos(a.theta), s = Math.sin(a.theta);
  return { x: c * dx + s * dy, y: -s * dx + c * dy, theta: b.theta - a.theta };
};

// The pose of `poses` (sorted by t) at time t, interpolated.
function poseAt(poses, t) {
  if (!poses.length) return null;
  if (t <= poses[0].t) return poses[0];
  for (let i = 1; i < poses.length; i++) {
    if (poses[i].t >= t) {
      const a = poses[i - 1], b = poses[i], k = (t - a.t) / Math.max(b.t - a.t, 1e-9);
      const dth = Math.atan2(Math.sin(b.theta - a.theta), Math.cos(b.theta - a.theta));
      return { t, x: a.x + k * (b.x - a.x), y: a.y + k * (b.y - a.y), theta: a.theta + k * dth };
    }
  }
  return poses[poses.length - 1];
}

const state = {
  robot: { x: 0, y: 0, theta: 0, pan: 0, tilt: 0 },
  perspective: true, points: false, edges: false, fill: true, orbit: false,
  playing: false, speed: 10, t: 0, t0: 0, t1: 1, frames: 0, firstFrameMs: null,
  loaded: false, model: false,
};
window.twinViewer = state; // read back by the browser test

const container = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setSize(container.clientWidth, container.clientHeight);
renderer.setClearColor(0xffffff);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.AmbientLight(0xffffff, 0.55));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(3, -4, 8);
scene.add(sun);
const aspect = () => container.clientWidth / Math.max(container.clientHeight, 1);
const perspective = new THREE.PerspectiveCamera(STEP.fov, aspect(), 0.01, 200);
const orthographic = new THREE.OrthographicCamera(-STEP.ortho * aspect(), STEP.ortho * aspect(), STEP.ortho, -STEP.ortho, -200, 200);
for (const c of [perspective, orthographic]) c.up.set(0, 0, 1);
const orbit = new OrbitControls(perspective, renderer.domElement);
orbit.enabled = false;
renderer.domElement.addEventListener('pointerdown', () => { if (!state.orbit) setOrbit(true); });

function setOrbit(on) {
  state.orbit = on;
  orbit.enabled = on;
  $('mode').textContent = on ? 'orbit camera (mouse; v: back to the robot)' : 'camera on the virtual robot';
  if (on) {
    const r = state.robot;
    orbit.target.set(r.x + 2 * Math.cos(r.theta), r.y + 2 * Math.sin(r.theta), 0.5);
    orbit.update();
  }
}

function camera() { return state.perspective ? perspective : orthographic; }

// The camera on the virtual robot's head: heading + pan, tilt, 0.55 m up.
function placeCamera() {
  if (state.orbit) { orbit.update(); return; }
  const r = state.robot, yaw = r.theta + r.pan;
  const eye = new THREE.Vector3(r.x, r.y, STEP.eye);
  const look = new THREE.Vector3(Math.cos(yaw) * Math.cos(r.tilt), Math.sin(yaw) * Math.cos(r.tilt), Math.sin(r.tilt));
  for (const c of [perspective, orthographic]) {
    c.position.copy(eye);
    c.lookAt(eye.clone().add(look));
  }
}

// ——— The world ———
const layers = { world: null, scans: null };
function drawWorld(world) {
  const group = new THREE.Group();
  layers.world = group;
  const byMaterial = {};
  for (const f of world.faces) {
    const m = f.material;
    (byMaterial[m] ||= []).push(
      f.a[0], f.a[1], f.z[0], f.b[0], f.b[1], f.z[0], f.b[0], f.b[1], f.z[1],
      f.a[0], f.a[1], f.z[0], f.b[0], f.b[1], f.z[1], f.a[0], f.a[1], f.z[1]);
  }
  for (const [m, v] of Object.entries(byMaterial)) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(v, 3));
    g.computeVertexNormals();
    const glass = m === 'glass';
    group.add(new THREE.Mesh(g, new THREE.MeshLambertMaterial({
      color: COLOURS[m] ?? COLOURS.matte, side: THREE.DoubleSide,
      transparent: glass || m === 'matte', opacity: glass ? 0.35 : 0.75, depthWrite: !glass,
    })));
  }
  for (const c of world.caps) {
    const shape = new THREE.Shape(c.polygon.map((p) => new THREE.Vector2(p[0], p[1])));
    const g = new THREE.ShapeGeometry(shape);
    g.translate(0, 0, c.z);
    group.add(new THREE.Mesh(g, new THREE.MeshLambertMaterial({ color: COLOURS[c.material] ?? COLOURS.matte, side: THREE.DoubleSide })));
  }
  const grid = new THREE.GridHelper(60, 60, 0xbbbbbb, 0xe6e6e6);
  grid.rotation.x = Math.PI / 2;
  group.add(grid);
  scene.add(group);
}

function pathLine(poses, colour, dashed) {
  const pts = poses.map((p) => new THREE.Vector3(p.x, p.y, 0.02));
  const g = new THREE.BufferGeometry().setFromPoints(pts);
  const m = dashed
    ? new THREE.LineDashedMaterial({ color: colour, dashSize: 0.12, gapSize: 0.08 })
    : new THREE.LineBasicMaterial({ color: colour });
  const line = new THREE.Line(g, m);
  if (dashed) line.computeLineDistances();
  scene.add(line);
}

// A scan's points in the world: the laser frame (mount yaw, height, tilt) on the base pose.
function scanPoints(scan, base) {
  const out = [];
  const [mx, my, myaw] = scan.laser_mount ?? [0, 0, 0];
  const z0 = scan.laser_z ?? 0.3, tilt = scan.laser_tilt ?? 0;
  const laser = compose(base, { x: mx, y: my, theta: myaw });
  const b = -tilt, cb = Math.cos(b), sb = Math.sin(b);
  const c = Math.cos(laser.theta), s = Math.sin(laser.theta);
  for (let i = 0; i < scan.ranges.length; i++) {
    const r = scan.ranges[i];
    if (!(r > 0) || r >= scan.range_max) continue;
    const a = scan.angle_min + i * scan.angle_increment;
    const lx = r * Math.cos(a), ly = r * Math.sin(a);
    const fx = lx * cb, fz = -lx * sb; // pitch about the laser's y axis
    out.push(laser.x + c * fx - s * ly, laser.y + s * fx + c * ly, z0 + fz);
  }
  return out;
}

function robotBody(body) {
  const g = new THREE.Group();
  const cyl = new THREE.Mesh(new THREE.CylinderGeometry(body.radius_m, body.radius_m, body.height_m, 32),
    new THREE.MeshLambertMaterial({ color: COLOURS.robot }));
  cyl.rotation.x = Math.PI / 2;
  cyl.position.set(body.center_x_m ?? 0, 0, body.height_m / 2);
  g.add(cyl);
  const nose = new THREE.Mesh(new THREE.BoxGeometry(body.radius_m, 0.04, 0.04), new THREE.MeshLambertMaterial({ color: 0x222222 }));
  nose.position.set(body.radius_m / 2, 0, body.height_m + 0.03);
  g.add(nose);
  scene.add(g);
  return g;
}

// One wedge per transducer out to its echo (a short dashed ray for none), placed at the pose the
// ring was read from; shown once the replay reaches the reading.
function drawSonar(ring, geometry) {
  const group = new THREE.Group();
  const [x, y, th] = ring.truth;
  const half = geometry.cone_deg * deg / 2;
  const mat = new THREE.MeshBasicMaterial({ color: COLOURS.sonar, transparent: true, opacity: 0.25, side: THREE.DoubleSide });
  for (const r of ring.readings) {
    const a = th + r.sonar * 2 * Math.PI / geometry.count;
    const cx = x + Math.cos(th) * geometry.center_x_m, cy = y + Math.sin(th) * geometry.center_x_m;
    const ox = cx + geometry.ring_radius_m * Math.cos(a), oy = cy + geometry.ring_radius_m * Math.sin(a);
    const d = r.distance_m;
    if (d == null) {
      const g = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(ox, oy, geometry.height_m), new THREE.Vector3(ox + 0.6 * Math.cos(a), oy + 0.6 * Math.sin(a), geometry.height_m)]);
      const line = new THREE.Line(g, new THREE.LineDashedMaterial({ color: COLOURS.sonar, dashSize: 0.05, gapSize: 0.05 }));
      line.computeLineDistances();
      group.add(line);
      continue;
    }
    const pts = [ox, oy, geometry.height_m];
    for (let k = 0; k <= 8; k++) {
      const b = a - half + 2 * half * k / 8;
      pts.push(ox + d * Math.cos(b), oy + d * Math.sin(b), geometry.height_m);
    }
    const idx = [];
    for (let k = 1; k <= 8; k++) idx.push(0, k, k + 1);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
    g.setIndex(idx);
    group.add(new THREE.Mesh(g, mat));
  }
  group.userData.t = ring.t;
  group.visible = false;
  scene.add(group);
  return group;
}

let modelMesh = null, modelPoints = null, modelEdges = null;
function applyModelStyle() {
  if (!modelMesh) return;
  modelMesh.visible = !state.points;
  modelPoints.visible = state.points;
  modelMesh.material.wireframe = !state.fill;
  modelEdges.visible = state.edges && !state.points;
}

// ——— Loading ———
const run = { scans: [], truth: [], odometry: [], estimate: [], placed: [], robot: null, current: null, sonar: null };
async function load() {
  const summaryText = await fetchText('summary.json', true);
  if (!summaryText) { $('title').textContent = 'not a run'; return; }
  const summary = JSON.parse(summaryText);
  $('title').textContent = `${summary.scenario ?? summary.log ?? 'run'} — seed ${summary.seed ?? '-'}`;
  $('figures').textContent = [
    summary.sim_seconds != null ? `${summary.sim_seconds.toFixed(1)} s simulated` : null,
    summary.scans != null ? `${summary.scans} scans` : null,
    summary.distance_m != null ? `${summary.distance_m.toFixed(2)} m driven` : null,
  ].filter(Boolean).join(', ');
  const worldText = await fetchText('world.json', false);
  let world = null;
  if (worldText) { world = JSON.parse(worldText); drawWorld(world); }
  else note('world.json is missing: the world is not drawn (a real drive or an older run).');
  run.truth = parseTum(await fetchText('truth.tum', false));
  run.odometry = parseTum(await fetchText('odometry.tum', false));
  run.estimate = parseTum(await fetchText('estimate.tum', false));
  if (!run.truth.length && !run.odometry.length) note('neither truth.tum nor odometry.tum: no path to replay.');
  const scansText = await fetchText('scans.jsonl', false);
  if (scansText) {
    for (const line of scansText.split('\n')) { if (line.trim()) { try { run.scans.push(JSON.parse(line)); } catch (e) { note(`scans.jsonl: a line is not JSON (${e.message})`); break; } } }
  } else note('scans.jsonl is missing: no scans drawn.');
  const legend = [];
  if (run.truth.length) { pathLine(run.truth, COLOURS.truth, false); legend.push(['true path', COLOURS.truth]); }
  if (run.odometry.length) { pathLine(run.odometry, COLOURS.odometry, true); legend.push(['odometry (dashed)', COLOURS.odometry]); }
  if (run.estimate.length) { pathLine(run.estimate, COLOURS.estimate, false); legend.push(['scan-matching estimate', COLOURS.estimate]); }
  // Scans placed at the estimate (dead-reckoned from the last estimate by odometry between
  // estimates), else at the truth, else at odometry.
  const by = run.estimate.length ? 'estimate' : run.truth.length ? 'true pose' : 'odometry';
  let last = null, k = 0;
  const all = [];
  for (const scan of run.scans) {
    const odo = { x: scan.odometry[0], y: scan.odometry[1], theta: scan.odometry[2] };
    let base;
    if (run.estimate.length) {
      while (k < run.estimate.length && run.estimate[k].t <= scan.t + 1e-6) { last = { est: run.estimate[k], odo }; k++; }
      base = last ? compose(last.est, relative(last.odo, odo)) : odo;
    } else if (run.truth.length) base = poseAt(run.truth, scan.t);
    else base = odo;
    const pts = scanPoints(scan, base);
    run.placed.push(pts);
    for (const v of pts) all.push(v);
  }
  if (all.length) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(all, 3));
    layers.scans = new THREE.Points(g, new THREE.PointsMaterial({ color: COLOURS.scans, size: 2, sizeAttenuation: false, transparent: true, opacity: 0.35 }));
    scene.add(layers.scans);
    legend.push([`scans placed at the ${by}`, COLOURS.scans]);
    const cg = new THREE.BufferGeometry();
    cg.setAttribute('position', new THREE.Float32BufferAttribute([], 3));
    run.current = new THREE.Points(cg, new THREE.PointsMaterial({ color: COLOURS.current, size: 4, sizeAttenuation: false }));
    scene.add(run.current);
    legend.push(['the scan of this instant', COLOURS.current]);
  }
  if (world) { run.robot = robotBody(world.robot); legend.push(['the robot (true pose)', COLOURS.robot]); }
  // The sonar ring's reading (sonar.json: one full ring, read at the end of the run).
  const sonarText = await fetchText('sonar.json', false);
  if (sonarText && world && world.robot.sonar) {
    run.sonar = drawSonar(JSON.parse(sonarText), world.robot.sonar);
    legend.push(['sonar ring: echoes of its reading', COLOURS.sonar]);
  }
  // The 3D model.
  const ply = await fetch('/run/model.ply');
  if (ply.ok) {
    const geometry = new PLYLoader().parse(await ply.arrayBuffer());
    if (!geometry.getAttribute('normal')) geometry.computeVertexNormals();
    modelMesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: COLOURS.model, side: THREE.DoubleSide }));
    modelPoints = new THREE.Points(geometry, new THREE.PointsMaterial({ color: 0x555555, size: 1.5, sizeAttenuation: false }));
    modelEdges = new THREE.LineSegments(new THREE.WireframeGeometry(geometry), new THREE.LineBasicMaterial({ color: 0x666666, transparent: true, opacity: 0.4 }));
    scene.add(modelMesh, modelPoints, modelEdges);
    state.model = true;
    legend.push([`3D model (${geometry.getAttribute('position').count.toLocaleString('en')} vertices)`, COLOURS.model]);
    applyModelStyle();
  }
  $('legend').innerHTML = legend.map(([t, c]) => `<span><i style="background:#${c.toString(16).padStart(6, '0')}"></i>${t}</span>`).join('');
  const times = run.scans.map((s) => s.t).concat(run.truth.map((p) => p.t));
  if (run.sonar) times.push(run.sonar.userData.t);
  state.t0 = times.length ? Math.min(...times) : 0;
  state.t1 = times.length ? Math.max(...times) : 1;
  state.t = state.t0;
  const start = run.truth[0] ?? run.odometry[0] ?? (world ? { x: world.start[0], y: world.start[1], theta: world.start[2] } : { x: 0, y: 0, theta: 0 });
  Object.assign(state.robot, { x: start.x, y: start.y, theta: start.theta, pan: 0, tilt: 0 });
  const params = new URLSearchParams(location.search);
  if (params.has('at')) state.t = state.t0 + (state.t1 - state.t0) * Math.min(Math.max(Number(params.get('at')) || 0, 0), 1);
  if (params.get('view') === 'overview' && world) overview(world);
  if (params.get('world') === 'off' && layers.world) layers.world.visible = false;
  if (params.get('scans') === 'off' && layers.scans) layers.scans.visible = false;
  showInstant();
  state.loaded = true;
}

// The orbit camera looking down on the whole world from its south side (`?view=overview`).
function overview(world) {
  const xs = world.faces.flatMap((f) => [f.a[0], f.b[0]]), ys = world.faces.flatMap((f) => [f.a[1], f.b[1]]);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2, size = Math.max(x1 - x0, y1 - y0);
  setOrbit(true);
  perspective.position.set(cx, cy - 0.75 * size, 0.7 * size);
  orbit.target.set(cx, cy, 0);
  orbit.update();
}

// The replay: the robot at its true pose (odometry without truth), the scan of that instant.
function showInstant() {
  const t = state.t;
  $('clock').textContent = `t = ${t.toFixed(1)} s`;
  $('time').value = Math.round(1000 * (t - state.t0) / Math.max(state.t1 - state.t0, 1e-9));
  const pose = poseAt(run.truth.length ? run.truth : run.odometry, t);
  if (run.robot && pose) { run.robot.position.set(pose.x, pose.y, 0); run.robot.rotation.z = pose.theta; }
  if (run.sonar) run.sonar.visible = t >= run.sonar.userData.t - 1e-6;
  let i = -1;
  for (let k = 0; k < run.scans.length; k++) if (run.scans[k].t <= t + 1e-6) i = k;
  if (run.current && i >= 0) {
    run.current.geometry.setAttribute('position', new THREE.Float32BufferAttribute(run.placed[i], 3));
    run.current.geometry.computeBoundingSphere();
    const s = run.scans[i];
    const head = s.head_pan != null ? `, head pan ${(s.head_pan / deg).toFixed(1)}°, tilt ${(s.head_tilt / deg).toFixed(1)}°` : '';
    $('state').textContent = `scan ${i + 1} of ${run.scans.length} at ${s.t.toFixed(2)} s, laser tilt ${((s.laser_tilt ?? 0) / deg).toFixed(1)}°${head}`;
  }
}

// ——— Input ———
export function press(key) {
  const r = state.robot;
  switch (key) {
    case 'ArrowUp': r.x += STEP.move * Math.cos(r.theta); r.y += STEP.move * Math.sin(r.theta); break;
    case 'ArrowDown': r.x -= STEP.move * Math.cos(r.theta); r.y -= STEP.move * Math.sin(r.theta); break;
    case 'ArrowLeft': r.theta += STEP.turn; break;
    case 'ArrowRight': r.theta -= STEP.turn; break;
    case 'a': r.pan += STEP.pan; break;
    case 'd': r.pan -= STEP.pan; break;
    case 'w': r.tilt = Math.min(r.tilt + STEP.tilt, 90 * deg); break;
    case 's': r.tilt = Math.max(r.tilt - STEP.tilt, -90 * deg); break;
    case 'p': state.perspective = true; break;
    case 'o': state.perspective = false; break;
    case 'x': state.points = !state.points; applyModelStyle(); break;
    case 'c': state.edges = !state.edges; applyModelStyle(); break;
    case 'f': state.fill = !state.fill; applyModelStyle(); break;
    case 'v': setOrbit(!state.orbit); break;
    case 'h': if (layers.world) layers.world.visible = !layers.world.visible; break;
    case 'k': if (layers.scans) layers.scans.visible = !layers.scans.visible; break;
    case ' ': togglePlay(); break;
    default: return false;
  }
  if (key.startsWith('Arrow') || 'adws'.includes(key)) { if (state.orbit) setOrbit(false); }
  return true;
}
window.addEventListener('keydown', (e) => { if (press(e.key)) e.preventDefault(); });

function togglePlay() {
  state.playing = !state.playing;
  $('play').textContent = state.playing ? '❚❚ pause' : '▶ play';
}
$('play').addEventListener('click', togglePlay);
$('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
$('time').addEventListener('input', (e) => { state.t = state.t0 + (state.t1 - state.t0) * Number(e.target.value) / 1000; showInstant(); });
$('png').addEventListener('click', () => {
  const a = document.createElement('a');
  a.href = renderer.domElement.toDataURL('image/png');
  a.download = `twin-view-${Date.now()}.png`;
  a.click();
});

// A gamepad through the Gamepad API: left stick moves and turns, right stick pans and tilts,
// at the keys' steps per frame while held past a dead zone.
function pollGamepad() {
  const pads = navigator.getGamepads ? navigator.getGamepads() : [];
  for (const pad of pads) {
    if (!pad) continue;
    const dead = 0.3, ax = pad.axes;
    if (ax[1] < -dead) press('ArrowUp');
    if (ax[1] > dead) press('ArrowDown');
    if (ax[0] < -dead) press('ArrowLeft');
    if (ax[0] > dead) press('ArrowRight');
    if (ax.length > 3) {
      if (ax[2] < -dead) state.robot.pan += STEP.pan / 10;
      if (ax[2] > dead) state.robot.pan -= STEP.pan / 10;
      if (ax[3] < -dead) press('w');
      if (ax[3] > dead) press('s');
    }
  }
}

window.addEventListener('resize', () => {
  renderer.setSize(container.clientWidth, container.clientHeight);
  perspective.aspect = aspect();
  perspective.updateProjectionMatrix();
  Object.assign(orthographic, { left: -STEP.ortho * aspect(), right: STEP.ortho * aspect() });
  orthographic.updateProjectionMatrix();
});

let lastFrame = performance.now();
function frame(now) {
  const dt = Math.min((now - lastFrame) / 1000, 0.25);
  lastFrame = now;
  pollGamepad();
  if (state.playing) {
    state.t += dt * state.speed;
    if (state.t >= state.t1) { state.t = state.t1; togglePlay(); }
    showInstant();
  }
  placeCamera();
  renderer.render(scene, camera());
  state.frames += 1;
  if (state.loaded && state.firstFrameMs == null) state.firstFrameMs = performance.now();
  requestAnimationFrame(frame);
}

// The browser test's self-check (`?selftest`): after loading, count the pixels that are not the
// background, press the thesis's keys and read the camera back, measure frames per second while
// navigating, and report it all to the server.
async function selftest() {
  const gl = renderer.getContext();
  const count = () => {
    renderer.render(scene, camera());
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight, px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let n = 0;
    const colours = new Set();
    for (let i = 0; i < px.length; i += 4) {
      if (px[i] < 250 || px[i + 1] < 250 || px[i + 2] < 250) n++;
      colours.add((px[i] >> 4) * 256 + (px[i + 1] >> 4) * 16 + (px[i + 2] >> 4));
    }
    return { drawn: n, of: w * h, colours: colours.size };
  };
  const pixels = count();
  const r = state.robot, before = { ...r };
  const snap = () => ({ ...state.robot, perspective: state.perspective, points: state.points, edges: state.edges, fill: state.fill });
  const keys = {};
  for (const k of ['ArrowUp', 'ArrowLeft', 'a', 'w', 'o', 'p', 'x', 'c', 'f']) { press(k); keys[k] = snap(); }
  for (let i = 0; i < 40; i++) press('w');
  keys.w40 = snap();
  press('x'); press('c'); press('f');
  // A gamepad: the left stick pushed forward for one poll moves the robot one step.
  const realPads = navigator.getGamepads;
  navigator.getGamepads = () => [{ axes: [0, -1, 0, 0], buttons: [] }];
  pollGamepad();
  navigator.getGamepads = realPads;
  keys.gamepadForward = snap();
  // The PNG the save button downloads.
  const png = renderer.domElement.toDataURL('image/png');
  // Navigate for two seconds of real time and count frames.
  const frames0 = state.frames, t0 = performance.now();
  await new Promise((resolve) => {
    const step = () => { press('ArrowUp'); press('ArrowLeft'); if (performance.now() - t0 < 2000) requestAnimationFrame(step); else resolve(); };
    requestAnimationFrame(step);
  });
  const fps = (state.frames - frames0) / ((performance.now() - t0) / 1000);
  const report = {
    pixels, before, keys, fps, png: { type: png.slice(0, 14), bytes: Math.floor(png.length * 3 / 4) }, firstFrameMs: state.firstFrameMs, model: state.model,
    scans: run.scans.length, messages, webgl: renderer.capabilities.isWebGL2 ? 2 : 1,
  };
  await fetch('/selftest', { method: 'POST', body: JSON.stringify(report) });
}

requestAnimationFrame(frame);
load().then(async () => {
  if (new URLSearchParams(location.search).has('selftest')) {
    while (state.firstFrameMs == null) await new Promise((r) => setTimeout(r, 20));
    await selftest();
  }
}).catch((e) => note(`the viewer failed: ${e.message}`));
