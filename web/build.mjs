// Builds the page penumbra-study serve ships (docs/study-online.md): jsPsych and its plugins from
// node_modules (pinned in package.json, installed by npm ci) copied beside the page's own files
// into dist/. Nothing is fetched at run time: the server serves dist/ as it is.
import { copyFileSync, mkdirSync, readdirSync, rmSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const out = process.argv[2] ?? join(here, "dist");
rmSync(out, { recursive: true, force: true });
mkdirSync(out, { recursive: true });
const modules = join(here, "node_modules");
const copies = {
  "jspsych.js": "jspsych/dist/index.browser.min.js",
  "jspsych.css": "jspsych/css/jspsych.css",
  "plugin-fullscreen.js": "@jspsych/plugin-fullscreen/dist/index.browser.min.js",
  "plugin-survey-html-form.js": "@jspsych/plugin-survey-html-form/dist/index.browser.min.js",
  "plugin-virtual-chinrest.js": "@jspsych/plugin-virtual-chinrest/dist/index.browser.min.js",
};
for (const [name, from] of Object.entries(copies)) copyFileSync(join(modules, from), join(out, name));
for (const name of readdirSync(join(here, "src"))) copyFileSync(join(here, "src", name), join(out, name));
console.log(`web: wrote ${out}`);
