// Headless Chromium for the tests' scripts: Debian's chromium driven by playwright-core, WebGL in software, no
// background networking; and a page's errors and network requests collected into a result.
import { chromium } from "playwright-core";

export function launch() {
  return chromium.launch({
    executablePath: process.env.P2N_CHROMIUM ?? "/usr/bin/chromium",
    args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-gpu-sandbox",
           "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"],
  });
}

// Collects into result.errors the page's errors and console errors, and into result.requests (when it has one)
// every request that leaves the page (not data:, blob: or file:).
export function watch(page, result) {
  page.on("pageerror", (e) => result.errors.push(String(e)));
  page.on("console", (m) => { if (m.type() === "error") result.errors.push(m.text()); });
  if (result.requests) {
    page.on("request", (r) => { if (!/^(data|blob|file):/.test(r.url())) result.requests.push(r.url()); });
  }
}
