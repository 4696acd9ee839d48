// Opens a report page in headless Chromium and prints one line of JSON: the page's errors, the network requests it
// made, whether its mesh view drew, and the share of that canvas the mesh covers (pixels unlike the clear colour).
//   node report_mesh_check.mjs REPORT.html [SCREENSHOT.png]
import { launch, watch } from "./browser.mjs";
import { writeFileSync } from "node:fs";
import { pathToFileURL } from "node:url";

const browser = await launch();
const result = { errors: [], requests: [] };
try {
  const page = await browser.newPage();
  watch(page, result);
  await page.goto(pathToFileURL(process.argv[2]).href, { waitUntil: "load" });
  await page.evaluate(() => window.p2nMesh.shown);
  result.shown = true;
  const frame = await page.evaluate(() => document.getElementById("p2n-mesh-canvas").toDataURL("image/png"));
  if (process.argv[3]) writeFileSync(process.argv[3], Buffer.from(frame.split(",")[1], "base64"));
  result.covered = await page.evaluate(async (src) => {
    const image = new Image();
    image.src = src;
    await image.decode();
    const canvas = new OffscreenCanvas(image.width, image.height);
    const context = canvas.getContext("2d");
    context.drawImage(image, 0, 0);
    const pixels = context.getImageData(0, 0, image.width, image.height).data;
    let drawn = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      drawn += Math.abs(pixels[i] - 0x20) + Math.abs(pixels[i + 1] - 0x20) + Math.abs(pixels[i + 2] - 0x20) > 6;
    }
    return drawn / (pixels.length / 4);
  }, frame);
} catch (error) {
  result.errors.push(String(error));
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
