// Opens a viewer page in headless Chromium and prints what it found, as JSON: whether the page loaded without
// errors or network requests, the PSNR between the frame it drew from a chosen camera and a reference image (our
// CPU rasterizer's render of the same camera), and whether a mouse drag changed the picture.
//   node viewer_check.mjs VIEWER.html CAMERA_NAME REFERENCE.png [SCREENSHOT.png]
import { launch, watch } from "./browser.mjs";
import { readFileSync, writeFileSync } from "node:fs";
import { pathToFileURL } from "node:url";

const [page_path, camera_name, reference_path, screenshot_path] = process.argv.slice(2);
const browser = await launch();
const result = { errors: [], requests: [] };
try {
  const page = await browser.newPage();
  watch(page, result);
  const url = `${pathToFileURL(page_path)}#camera=${encodeURIComponent(camera_name)}&size=native`;
  await page.goto(url, { waitUntil: "load" });
  await page.evaluate(() => window.p2n.loaded);
  // Spark sorts the splats in a worker and draws none before its first sort: wait for two frames that agree, the
  // first taken after a sort had finished. (Two blank frames agree too: a slow worker once let CI compare one.)
  const snapshot = () => page.evaluate(() => document.getElementById("p2n-canvas").toDataURL("image/png"));
  const settled = async () => {
    let previous = "", sorted_before_previous = false;
    for (let i = 0; i < 40; ++i) {
      await page.evaluate(() => new Promise((done) => setTimeout(done, 250)));
      const sorted = await page.evaluate(() => window.p2n.sorted());
      const now = await snapshot();
      if (now === previous && sorted_before_previous) return now;
      [previous, sorted_before_previous] = [now, sorted];
    }
    return previous;
  };
  const before = await settled();
  const reference = `data:image/png;base64,${readFileSync(reference_path).toString("base64")}`;
  result.psnr = await page.evaluate(async ([a, b]) => {
    const pixels = async (src) => {
      const image = new Image();
      image.src = src;
      await image.decode();
      const c = new OffscreenCanvas(image.width, image.height);
      const g = c.getContext("2d");
      g.drawImage(image, 0, 0);
      return g.getImageData(0, 0, image.width, image.height);
    };
    const [x, y] = [await pixels(a), await pixels(b)];
    if (x.width !== y.width || x.height !== y.height) return `sizes differ: ${x.width}x${x.height} and ${y.width}x${y.height}`;
    let sum = 0, n = 0;
    for (let i = 0; i < x.data.length; i += 4) {
      for (let c = 0; c < 3; ++c, ++n) sum += ((x.data[i + c] - y.data[i + c]) / 255) ** 2;
    }
    return -10 * Math.log10(Math.max(sum / n, 1e-12));
  }, [before, reference]);
  if (screenshot_path) writeFileSync(screenshot_path, Buffer.from(before.split(",")[1], "base64"));
  // The whole canvas inside the window, so that the drag reaches it.
  const size = await page.evaluate(() => {
    const canvas = document.getElementById("p2n-canvas");
    return [canvas.width, canvas.height];
  });
  await page.setViewportSize({ width: Math.max(size[0], 320), height: size[1] + 120 });
  const box = await page.locator("#p2n-canvas").boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.8, box.y + box.height / 2, { steps: 8 });
  await page.mouse.up();
  result.drag_changed_picture = (await settled()) !== before;
} catch (error) {
  result.errors.push(String(error));
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
