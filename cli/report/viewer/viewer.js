// The campaign viewer (index.html; docs/viewer.md): the models of every
// workflow of a scene side by side, one shared camera (orbit, or walk at eye
// height from the scene's viewpoints), toggles for the color map, the normal
// map, wireframe and PNG/KTX2 textures, each model's figures, and WebXR.
//
// Lighting is the reference renderer's (stages/geometry/render/render.h):
// albedo * (0.25 + 0.75 * max(0, N.L)), two-sided, with a headlight fixed to
// the camera at (-0.15, 0.25, -1) in its frame (x right, y up, z forward),
// so that a view shows what render.frames drew from the same viewpoint.
//
// URL parameters: scene=NAME, run=NAME (only that run), view=NAME (start at
// that viewpoint), textures=png|ktx2, color=0|1, normal=0|1, wire=0|1 (the
// toggles' first state), test=SIZE (for the browser test: only
// the canvas, SIZE x SIZE pixels, transparent background, no UI).
// window.pbViewer.ready turns true once every shown model is loaded and
// drawn; window.pbViewer.error holds the first error (also console.error).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { VRButton } from 'three/addons/webxr/VRButton.js';

const AMBIENT = 0.25, DIFFUSE = 0.75;              // render.h RenderOptions defaults
const LIGHT_CAMERA = [-0.15, 0.25, -1.0];          // toward the light, camera frame, z forward
const WALK_SPEED_M_S = 1.4, XR_EYE_HEIGHT_M = 1.6;

const params = new URLSearchParams(location.search);
const testSize = Number(params.get('test') || 0);
const state = window.pbViewer = { ready: false, error: null, models: [] };
function fail(message) {
  if (!state.error) state.error = message;
  console.error('pointbake viewer: ' + message);
}
window.addEventListener('error', (e) => fail(String(e.message)));
window.addEventListener('unhandledrejection', (e) => fail(String(e.reason && e.reason.message || e.reason)));

const $ = (id) => document.getElementById(id);
if (testSize) { document.documentElement.classList.add('test'); document.body.classList.add('test'); }

// Scene coordinates (z up, absolute meters) to three's (glTF's y up) relative
// to `ref`, the scene's reference origin: (x, y, z) -> (x, z, -y).
const toThree = (p, ref = [0, 0, 0]) => new THREE.Vector3(p[0] - ref[0], p[2] - ref[2], -(p[1] - ref[1]));
const dirToThree = (d) => new THREE.Vector3(d[0], d[2], -d[1]);

const canvas = $('canvas');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, alpha: true, preserveDrawingBuffer: !!testSize });
renderer.setPixelRatio(testSize ? 1 : window.devicePixelRatio);
renderer.setClearColor(0x000000, testSize ? 0 : 1);
renderer.xr.enabled = true;
const camera = new THREE.PerspectiveCamera(60, 1, 0.01, 2000);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = false;

const ktx2 = new KTX2Loader().setTranscoderPath('./lib/addons/libs/basis/').detectSupport(renderer);
const loader = new GLTFLoader().setKTX2Loader(ktx2);

let index = null;      // models.json
let sceneInfo = null;  // the shown scene's entry
let reference = [0, 0, 0];
let cells = [];        // {model, element, scene, world, light, meshes}
let walkHeight = null;

function fmtBytes(b) { return b == null ? '—' : (b / 1048576).toFixed(1) + ' MiB'; }
function fmt(v, digits) { return v == null ? '—' : Number(v).toFixed(digits); }

function figuresHtml(model, loaded) {
  const f = model.figures || {};
  const tex = loaded && loaded.texture ? `${loaded.texture.width}×${loaded.texture.height}` :
              f.texture_width ? `${f.texture_width}×${f.texture_height}` : 'none';
  return `<b>${model.title}</b><br>` +
    `${loaded ? loaded.faces.toLocaleString('en') : (f.faces || 0).toLocaleString('en')} faces · maps ${tex}` +
    (loaded && loaded.gpu_bytes != null ? ` · GPU ${fmtBytes(loaded.gpu_bytes)} (RGBA8)` :
     ` · GPU ${fmtBytes(f.texture_bytes)}${loaded && loaded.ktx2 ? ' (KTX2)' : ''}`) + '<br>' +
    `est. ${fmt(f.fps, 0)} FPS (${f.device || '?'})` +
    (f.flip_truth != null ? ` · FLIP ${fmt(f.flip_truth, 3)} · MS-SSIM ${fmt(f.ms_ssim_truth, 3)} vs truth` :
     f.flip_hpm != null ? ` · FLIP ${fmt(f.flip_hpm, 3)} vs HPM` : '') +
    (loaded && loaded.file ? `<br>${loaded.file}` : '');
}

function applyToggles() {
  const color = $('color').checked, normal = $('normal').checked, wire = $('wire').checked;
  for (const cell of cells) {
    for (const mesh of cell.meshes) {
      const m = mesh.material;
      m.map = color ? mesh.userData.map : null;
      m.normalMap = normal ? mesh.userData.normalMap : null;
      m.wireframe = wire;
      m.needsUpdate = true;
    }
  }
}

function setViewpoint(vp) {
  camera.position.copy(toThree(vp.eye, reference));
  camera.up.copy(dirToThree(vp.up || [0, 0, 1]).normalize());
  const target = toThree(vp.target, reference);
  camera.lookAt(target);
  camera.fov = vp.fov_deg || 60;
  camera.updateProjectionMatrix();
  controls.target.copy(target);
  walkHeight = camera.position.y;
  controls.update();
}

// Replaces the glTF material by a Lambert one lit as the reference renderer.
function prepare(gltf, file) {
  const meshes = [], maps = [];
  let faces = 0, texture = null;
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    const m = o.material;
    const lambert = new THREE.MeshLambertMaterial({
      color: m.color, map: m.map, normalMap: m.normalMap, vertexColors: m.vertexColors, side: THREE.DoubleSide });
    if (m.normalMap) lambert.normalScale.copy(m.normalScale);
    o.userData.map = m.map;
    o.userData.normalMap = m.normalMap;
    o.material = lambert;
    meshes.push(o);
    const index = o.geometry.index;
    faces += (index ? index.count : o.geometry.attributes.position.count) / 3;
    if (m.map && m.map.image) texture = { width: m.map.image.width, height: m.map.image.height };
    for (const t of [m.map, m.normalMap]) if (t && t.image && !maps.includes(t)) maps.push(t);
  });
  // PNG maps take RGBA8 with a full mip chain (4/3) on the GPU; KTX2 maps
  // count with the figure estimate.fps computed from their blocks.
  const ktx2 = maps.some((t) => t.isCompressedTexture);
  const gpu_bytes = ktx2 ? null : maps.reduce((sum, t) => sum + Math.round(4 * t.image.width * t.image.height * 4 / 3), 0);
  return { meshes, faces, texture, file, ktx2, gpu_bytes };
}

function originOf(gltf) {
  const root = gltf.scene.children[0];
  const o = root && root.userData && root.userData.pointbake_origin;
  if (Array.isArray(o) && o.length === 3) return o;
  return root ? [root.position.x, -root.position.z, root.position.y] : [0, 0, 0];
}

async function showScene(name) {
  state.ready = false;
  for (const cell of cells) cell.element.remove();
  cells = [];
  sceneInfo = index.scenes.find((s) => s.name === name);
  if (!sceneInfo) { fail(`no scene '${name}' in models.json`); return; }
  const runFilter = params.get('run');
  const models = sceneInfo.models.filter((m) => !runFilter || m.run === runFilter);
  if (!models.length) { fail(`no model to show (scene '${name}'${runFilter ? `, run '${runFilter}'` : ''})`); return; }
  const grid = $('grid');
  const columns = Math.ceil(Math.sqrt(models.length));
  grid.style.gridTemplateColumns = `repeat(${columns}, 1fr)`;
  grid.style.gridTemplateRows = `repeat(${Math.ceil(models.length / columns)}, 1fr)`;
  const views = $('view');
  views.innerHTML = '';
  for (const vp of sceneInfo.viewpoints) views.add(new Option(vp.name, vp.name));
  const wanted = params.get('view');
  if (wanted && sceneInfo.viewpoints.some((v) => v.name === wanted)) views.value = wanted;

  const useKtx2 = $('textures').value === 'ktx2';
  for (const model of models) {
    const element = document.createElement('div');
    element.className = 'cell';
    element.innerHTML = `<div class="figures">${figuresHtml(model, null)}<br>loading…</div>`;
    grid.appendChild(element);
    const scene = new THREE.Scene();
    const world = new THREE.Group();
    scene.add(world);
    scene.add(new THREE.AmbientLight(0xffffff, Math.PI * AMBIENT));  // three divides by pi
    const light = new THREE.DirectionalLight(0xffffff, Math.PI * DIFFUSE);
    scene.add(light, light.target);
    cells.push({ model, element, scene, world, light, meshes: [] });
  }
  const loads = cells.map(async (cell) => {
    const file = useKtx2 && cell.model.glb_ktx2 ? cell.model.glb_ktx2 : cell.model.glb;
    try {
      const gltf = await loader.loadAsync(file);
      cell.gltf = gltf;
      cell.loaded = prepare(gltf, file.split('/').slice(-1)[0]);
      cell.meshes = cell.loaded.meshes;
    } catch (e) {
      cell.element.querySelector('.figures').innerHTML = `${figuresHtml(cell.model, null)}<br><span class="error">${file}: ${e.message || e}</span>`;
      fail(`${file}: ${e.message || e}`);
    }
  });
  await Promise.all(loads);
  const first = cells.find((c) => c.gltf);
  if (!first) return;
  reference = originOf(first.gltf);
  for (const cell of cells) {
    if (!cell.gltf) continue;
    const root = cell.gltf.scene.children[0];
    root.position.copy(toThree(originOf(cell.gltf), reference));
    cell.world.add(cell.gltf.scene);
    cell.element.querySelector('.figures').innerHTML = figuresHtml(cell.model, cell.loaded);
    state.models.push({ run: cell.model.run, file: cell.loaded.file, faces: cell.loaded.faces, texture: cell.loaded.texture,
                        normal_map: cell.meshes.some((m) => !!m.userData.normalMap) });
  }
  applyToggles();
  const vp = sceneInfo.viewpoints.find((v) => v.name === views.value) || sceneInfo.viewpoints[0];
  if (vp) setViewpoint(vp);
  else {
    const box = new THREE.Box3().setFromObject(first.world);
    controls.target.copy(box.getCenter(new THREE.Vector3()));
    camera.position.copy(box.max);
    controls.update();
  }
  // Ready after two drawn frames (the textures are uploaded on the first).
  let frames = 0;
  const tick = () => { if (++frames >= 2) { state.ready = !state.error; document.title += state.ready ? ' (ready)' : ' (error)'; } else requestAnimationFrame(tick); };
  requestAnimationFrame(tick);
}

// Walk: drag turns, W A S D / arrows move on the horizontal plane at the
// viewpoint's eye height.
const keys = new Set();
window.addEventListener('keydown', (e) => keys.add(e.key.toLowerCase()));
window.addEventListener('keyup', (e) => keys.delete(e.key.toLowerCase()));
let drag = null;
canvas.addEventListener('pointerdown', (e) => { if ($('mode').value === 'walk') drag = { x: e.clientX, y: e.clientY }; });
window.addEventListener('pointerup', () => { drag = null; });
window.addEventListener('pointermove', (e) => {
  if (!drag) return;
  const euler = new THREE.Euler().setFromQuaternion(camera.quaternion, 'YXZ');
  euler.y -= (e.clientX - drag.x) * 0.004;
  euler.x = Math.max(-1.5, Math.min(1.5, euler.x - (e.clientY - drag.y) * 0.004));
  euler.z = 0;
  camera.quaternion.setFromEuler(euler);
  drag = { x: e.clientX, y: e.clientY };
});
function walk(dt) {
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  forward.y = 0;
  if (forward.lengthSq() < 1e-9) return;
  forward.normalize();
  const right = new THREE.Vector3().crossVectors(forward, new THREE.Vector3(0, 1, 0));
  const step = WALK_SPEED_M_S * dt * (keys.has('shift') ? 3 : 1);
  if (keys.has('w') || keys.has('arrowup')) camera.position.addScaledVector(forward, step);
  if (keys.has('s') || keys.has('arrowdown')) camera.position.addScaledVector(forward, -step);
  if (keys.has('d') || keys.has('arrowright')) camera.position.addScaledVector(right, step);
  if (keys.has('a') || keys.has('arrowleft')) camera.position.addScaledVector(right, -step);
  if (walkHeight != null) camera.position.y = walkHeight;
}

const lightLocal = new THREE.Vector3(LIGHT_CAMERA[0], LIGHT_CAMERA[1], -LIGHT_CAMERA[2]);  // three looks down -z
function placeLight(cell, view) {
  cell.light.position.copy(lightLocal).applyQuaternion(view.quaternion).add(view.position);
  cell.light.target.position.copy(view.position);
  cell.light.target.updateMatrixWorld();
}

let last = performance.now(), frameCount = 0, fpsStart = last;
function render(now) {
  const dt = Math.min(0.1, (now - last) / 1000);
  last = now;
  if ($('mode').value === 'walk') walk(dt);
  if (renderer.xr.isPresenting) {
    const cell = cells.find((c) => c.gltf);
    if (!cell) return;
    const xrCamera = renderer.xr.getCamera();
    xrCamera.getWorldPosition(xrCamera.position);
    placeLight(cell, xrCamera);
    renderer.render(cell.scene, camera);
    return;
  }
  const width = testSize || canvas.clientWidth, height = testSize || canvas.clientHeight;
  if (canvas.width !== Math.floor(width * renderer.getPixelRatio()) || canvas.height !== Math.floor(height * renderer.getPixelRatio())) {
    renderer.setSize(width, height, !!testSize);
  }
  renderer.setScissorTest(true);
  renderer.setClearColor(0x000000, testSize ? 0 : 1);
  renderer.clear();
  const canvasRect = canvas.getBoundingClientRect();
  for (const cell of cells) {
    let x = 0, y = 0, w = width, h = height;
    if (!testSize) {
      const r = cell.element.getBoundingClientRect();
      x = r.left - canvasRect.left; w = r.width; h = r.height;
      y = canvasRect.height - (r.bottom - canvasRect.top);
    }
    if (w <= 0 || h <= 0) continue;
    renderer.setViewport(x, y, w, h);
    renderer.setScissor(x, y, w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    placeLight(cell, camera);
    renderer.render(cell.scene, camera);
  }
  renderer.setScissorTest(false);
  if (++frameCount && now - fpsStart > 1000) {
    $('fps').textContent = `browser ${(frameCount * 1000 / (now - fpsStart)).toFixed(0)} FPS`;
    frameCount = 0;
    fpsStart = now;
  }
}

renderer.xr.addEventListener('sessionstart', () => {
  // Stand the headset where the camera is: eye level at XR_EYE_HEIGHT_M above the floor.
  for (const cell of cells) cell.world.position.set(-camera.position.x, XR_EYE_HEIGHT_M - camera.position.y, -camera.position.z);
});
renderer.xr.addEventListener('sessionend', () => { for (const cell of cells) cell.world.position.set(0, 0, 0); });

async function main() {
  const response = await fetch('./models.json');
  if (!response.ok) throw new Error(`models.json: HTTP ${response.status}`);
  index = await response.json();
  if (index.format !== 'pointbake-viewer') throw new Error('models.json: not a pointbake-viewer index');
  $('title').textContent = `pointbake · ${index.campaign}`;
  document.title = `${index.campaign} · pointbake viewer`;
  const scenes = $('scene');
  for (const s of index.scenes) scenes.add(new Option(s.name, s.name));
  const run = params.get('run');
  const runScene = run && index.scenes.find((s) => s.models.some((m) => m.run === run));
  scenes.value = params.get('scene') || (runScene ? runScene.name : index.scenes[0] && index.scenes[0].name);
  if (params.get('textures') === 'ktx2') $('textures').value = 'ktx2';
  for (const id of ['color', 'normal', 'wire']) {
    if (params.has(id)) $(id).checked = params.get(id) === '1';
  }
  scenes.addEventListener('change', () => showScene(scenes.value));
  $('textures').addEventListener('change', () => showScene(scenes.value));
  $('view').addEventListener('change', () => {
    const vp = sceneInfo.viewpoints.find((v) => v.name === $('view').value);
    if (vp) setViewpoint(vp);
  });
  $('mode').addEventListener('change', () => {
    controls.enabled = $('mode').value === 'orbit';
    if (controls.enabled) {
      const dir = new THREE.Vector3();
      camera.getWorldDirection(dir);
      controls.target.copy(camera.position).addScaledVector(dir, 2);
      controls.update();
    } else {
      walkHeight = camera.position.y;
    }
  });
  for (const id of ['color', 'normal', 'wire']) $(id).addEventListener('change', applyToggles);
  if (!testSize) {
    const button = VRButton.createButton(renderer);
    document.body.appendChild(button);
  }
  renderer.setAnimationLoop(render);
  if (!index.scenes.length) { fail('models.json lists no scene'); return; }
  await showScene(scenes.value);
}
main().catch((e) => fail(e.message || String(e)));
