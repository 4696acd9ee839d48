// The report page's view of the textured mesh: three.js draws the glTF the page holds (base64 in a script
// element), and the mouse turns, pans and zooms round it. Everything it needs is in the page.
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

async function show() {
  const canvas = document.getElementById("p2n-mesh-canvas");
  const binary = atob(document.getElementById("p2n-mesh").textContent.replace(/\s+/g, ""));
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  const gltf = await new GLTFLoader().parseAsync(bytes.buffer, "");

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  renderer.setSize(canvas.clientWidth, canvas.clientHeight, false);
  renderer.setClearColor(0x202020, 1);
  const world = new THREE.Scene();
  world.add(gltf.scene);
  // The whole mesh in view, seen from 30 degrees above the horizontal (glTF's +Y is up).
  const bounds = new THREE.Box3().setFromObject(gltf.scene).getBoundingSphere(new THREE.Sphere());
  const camera = new THREE.PerspectiveCamera(40, canvas.clientWidth / canvas.clientHeight,
                                             bounds.radius / 100, bounds.radius * 100);
  const direction = new THREE.Vector3(Math.cos(Math.PI / 6) * 0.7, Math.sin(Math.PI / 6), Math.cos(Math.PI / 6) * 0.7);
  camera.position.copy(bounds.center).addScaledVector(direction.normalize(), bounds.radius * 2.4);
  const controls = new OrbitControls(camera, canvas);
  controls.target.copy(bounds.center);
  controls.update();
  const draw = () => renderer.render(world, camera);
  controls.addEventListener("change", draw);
  draw();
}

// For tests: resolves when the mesh is drawn, rejects with why it could not be.
window.p2nMesh = { shown: show() };
