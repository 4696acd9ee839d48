// The splat viewer page: three.js with Spark draws the scene's splats (embedded in the page as a compressed
// PLY), the camera starts at a training camera, any camera of the capture can be chosen, and the user orbits,
// pans and zooms with the mouse or touch, and flies with the keys. Everything it needs is in the page.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { SparkRenderer, SplatMesh } from "@sparkjsdev/spark";

const scene = JSON.parse(document.getElementById("p2n-scene").textContent);
const canvas = document.getElementById("p2n-canvas");
const select = document.getElementById("p2n-camera");
const status = document.getElementById("p2n-status");
document.title = scene.title;
document.getElementById("p2n-title").textContent = scene.title;
const params = new URLSearchParams(location.hash.slice(1));
const nativeSize = params.get("size") === "native";  // the canvas at the camera's own size (tests, screenshots)
if (nativeSize) document.getElementById("p2n-panel").style.position = "static";  // below the canvas, not over it

function base64Bytes(text) {
  const binary = atob(text.replace(/\s+/g, ""));
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(nativeSize ? 1 : Math.min(window.devicePixelRatio, 2));
// The background is a colour of the photos (sRGB), as the splats' colours are; three.js would take plain numbers
// for linear ones and brighten them on the way out.
renderer.setClearColor(new THREE.Color().setRGB(...scene.background, THREE.SRGBColorSpace), 1);
const world = new THREE.Scene();
const spark = new SparkRenderer({ renderer });
world.add(spark);
const splats = new SplatMesh({
  fileBytes: base64Bytes(document.getElementById("p2n-splats").textContent),
  fileName: "splats.compressed.ply",
});
world.add(splats);

const camera = new THREE.PerspectiveCamera(50, 1, scene.near, scene.far);
const up = new THREE.Vector3();
for (const view of scene.cameras) up.add(new THREE.Vector3(view.pose[4], view.pose[5], view.pose[6]));
camera.up.copy(up.lengthSq() > 0 ? up.normalize() : new THREE.Vector3(0, 1, 0));
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = false;
controls.screenSpacePanning = true;
controls.listenToKeyEvents(window);  // the arrow keys pan
let current = scene.cameras[0];

// Sizes the canvas (the window, or the camera's own pixels) and sets the projection of `current`.
function resize() {
  const width = nativeSize ? current.width : window.innerWidth;
  const height = nativeSize ? current.height : window.innerHeight;
  renderer.setSize(width, height, !nativeSize);
  const zoom = height / current.height;  // the photo's vertical field of view fills the canvas
  camera.fov = THREE.MathUtils.radToDeg(2 * Math.atan(current.height / 2 / current.fy));
  camera.aspect = width / height;
  // The principal point as far from the canvas's centre as the photo has it from its own.
  const dx = (current.width / 2 - current.cx) * zoom, dy = (current.height / 2 - current.cy) * zoom;
  camera.setViewOffset(width, height, dx, dy, width, height);
  camera.updateProjectionMatrix();
}

// Puts the camera where training camera `view` was; the orbit turns about the point it looks at, at the distance
// of the scene's centre.
function showCamera(view) {
  current = view;
  const pose = new THREE.Matrix4().fromArray(view.pose);  // column-major world_from_camera, OpenGL axes
  pose.decompose(camera.position, camera.quaternion, new THREE.Vector3());
  const forward = new THREE.Vector3(0, 0, -1).applyQuaternion(camera.quaternion);
  const centre = new THREE.Vector3(...scene.centre);
  const distance = Math.max(centre.clone().sub(camera.position).dot(forward), scene.near * 10);
  controls.target.copy(camera.position).addScaledVector(forward, distance);
  camera.updateMatrixWorld();
  select.value = view.name;
  resize();
}

for (const view of scene.cameras) {
  const option = document.createElement("option");
  option.value = view.name;
  option.textContent = `${view.split === "train" ? "training" : "held-out"}: ${view.name}`;
  select.append(option);
}
select.addEventListener("change", () => {
  showCamera(scene.cameras.find((v) => v.name === select.value));
  select.blur();  // the keys fly again
});
window.addEventListener("resize", resize);

// Flying: W/S forward and back, A/D sideways, R/F (or E/Q) up and down; Shift flies faster.
const keys = new Set();
window.addEventListener("keydown", (e) => { if (e.target === document.body) keys.add(e.code); });
window.addEventListener("keyup", (e) => keys.delete(e.code));
window.addEventListener("blur", () => keys.clear());
const moves = { KeyW: [0, 0, -1], KeyS: [0, 0, 1], KeyA: [-1, 0, 0], KeyD: [1, 0, 0],
                 KeyR: [0, 1, 0], KeyE: [0, 1, 0], KeyF: [0, -1, 0], KeyQ: [0, -1, 0] };
function fly(seconds) {
  const step = new THREE.Vector3();
  for (const code of keys) if (moves[code]) step.add(new THREE.Vector3(...moves[code]));
  if (step.lengthSq() === 0) return;
  const speed = scene.radius * 0.5 * (keys.has("ShiftLeft") || keys.has("ShiftRight") ? 4 : 1);
  step.normalize().multiplyScalar(speed * seconds).applyQuaternion(camera.quaternion);
  camera.position.add(step);
  controls.target.add(step);
}

const start = scene.cameras.find((v) => v.name === params.get("camera")) ??
              scene.cameras.find((v) => v.split === "train") ?? scene.cameras[0];
showCamera(start);
let frames = 0, last = performance.now();
renderer.setAnimationLoop((now) => {
  fly(Math.min((now - last) / 1000, 0.1));
  last = now;
  // No controls.update() here: it would turn the camera upright about the scene's up, and a photo's camera may
  // lean; the controls update themselves when the user drags.
  renderer.render(world, camera);
  ++frames;
});
splats.initialized.then(() => {
  status.textContent = `${splats.packedSplats?.numSplats ?? ""} splats`;
});

// For tests and scripts: the page's state and a way to choose a camera.
window.p2n = {
  loaded: splats.initialized,
  frames: () => frames,
  // Whether the splats drawn are in the order of a finished sort and no other is due: before the first sort
  // Spark draws none of them.
  sorted: () => spark.activeSplats > 0 && !spark.sorting && !spark.sortDirty,
  showCamera: (name) => showCamera(scene.cameras.find((v) => v.name === name)),
};
