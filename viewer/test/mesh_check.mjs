// Draws a glTF file with three.js's GLTFLoader in headless Chromium from given cameras and writes each frame as a
// PNG (OUT_DIR/0.png, 1.png, ... in the cameras' order); prints one line of JSON: the page's errors and the files.
//   node mesh_check.mjs MESH.glb CAMERAS.json OUT_DIR
// CAMERAS.json: {"background": [r, g, b] (0..1; without it the background is transparent), "near": n, "far": f, "cameras": [{"width", "height", "fx", "fy",
// "cx", "cy", "pose": world_from_camera in the glTF's frame, OpenGL axes, 16 numbers column-major}]}.
import { launch, watch } from "./browser.mjs";
import * as esbuild from "esbuild";
import { readFileSync, writeFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const [glb_path, cameras_path, out_dir] = process.argv.slice(2);
const here = dirname(fileURLToPath(import.meta.url));
const bundle = await esbuild.build({
  stdin: {
    contents: `import * as THREE from "three";
               import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
               window.THREE = THREE; window.GLTFLoader = GLTFLoader;`,
    resolveDir: here,
  },
  bundle: true, write: false, format: "iife", logLevel: "warning",
});
const browser = await launch();
const result = { errors: [], files: [] };
try {
  const page = await browser.newPage();
  watch(page, result);
  await page.setContent(`<canvas id="c"></canvas><script>${bundle.outputFiles[0].text}</script>`);
  const frames = await page.evaluate(async ([glb, setup]) => {
    const THREE = window.THREE;
    const bytes = Uint8Array.from(atob(glb), (c) => c.charCodeAt(0));
    const gltf = await new window.GLTFLoader().parseAsync(bytes.buffer, "");
    const world = new THREE.Scene();
    if (setup.background) world.background = new THREE.Color().setRGB(...setup.background, THREE.SRGBColorSpace);
    world.add(gltf.scene);
    const canvas = document.getElementById("c");
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, alpha: true, preserveDrawingBuffer: true });
    renderer.setClearColor(0x000000, 0);
    const frames = [];
    for (const view of setup.cameras) {
      renderer.setSize(view.width, view.height, false);
      const camera = new THREE.PerspectiveCamera(
          THREE.MathUtils.radToDeg(2 * Math.atan(view.height / 2 / view.fy)), view.width / view.height,
          setup.near, setup.far);
      camera.setViewOffset(view.width, view.height, view.width / 2 - view.cx, view.height / 2 - view.cy, view.width,
                           view.height);
      new THREE.Matrix4().fromArray(view.pose).decompose(camera.position, camera.quaternion, new THREE.Vector3());
      camera.updateMatrixWorld();
      renderer.render(world, camera);
      frames.push(canvas.toDataURL("image/png"));
    }
    return frames;
  }, [readFileSync(glb_path).toString("base64"), JSON.parse(readFileSync(cameras_path, "utf8"))]);
  frames.forEach((frame, i) => {
    const file = join(out_dir, `${i}.png`);
    writeFileSync(file, Buffer.from(frame.split(",")[1], "base64"));
    result.files.push(file);
  });
} catch (error) {
  result.errors.push(String(error));
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
