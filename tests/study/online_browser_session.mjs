// A whole short online session in a real browser (tests/study/online_test.cpp runs it): Debian's
// chromium, headless, driven by puppeteer-core from web/node_modules (nothing downloads a browser).
// Usage: node online_browser_session.mjs URL SCREENSHOT_DIR [ANSWERS] [RELOAD_AT]
//   URL: the participant link (http://127.0.0.1:PORT/?id=ID); ANSWERS: the key pressed on trial n
//   is ANSWERS[n % length], f (first) or j (second) (default "f"); RELOAD_AT: reload the page once
//   when trial RELOAD_AT is on screen, instead of answering it.
// Takes a screenshot of each new screen (NN-<screen>.png) and prints one line per step (on a
// trial, also how many images it shows: a frame study's sample above and the two below).
import { createRequire } from "node:module";
import { mkdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, "../../web/package.json"));
const puppeteer = require("puppeteer-core");

const [url, shots, answers = "f", reloadAtText = "-1"] = process.argv.slice(2);
const reloadAt = Number(reloadAtText);
let reloaded = false;
mkdirSync(shots, { recursive: true });
const browser = await puppeteer.launch({
  executablePath: process.env.PENUMBRA_CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--window-size=1280,800", "--disable-gpu", "--force-device-scale-factor=1"],
  defaultViewport: { width: 1280, height: 800 },
});
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let shot = 0, answered = 0, lastName = "", changed = Date.now();
try {
  const page = await browser.newPage();
  page.on("pageerror", (e) => console.log("page error: " + e.message));
  await page.goto(url, { waitUntil: "networkidle0" });
  const deadline = Date.now() + 240000;
  for (;;) {
    if (Date.now() > deadline || Date.now() - changed > 20000) {
      const dump = await page.evaluate(() => document.body.innerText.slice(0, 600) + "\nscreen: " + JSON.stringify(typeof screen === "object" ? screen : null).slice(0, 600));
      throw new Error(`stuck on '${lastName}' (${answered} trials answered): ${dump}`);
    }
    await sleep(150);
    const state = await page.evaluate(() => {
      const q = (s) => document.querySelector(s);
      if (q("#jspsych-fullscreen-btn")) return "fullscreen";
      if (q("#end_resize_phase")) return "chinrest-card";
      if (q("#svgDiv")) return "chinrest-blindspot";
      if (q("#distance-report") && q("#distance-report").offsetParent !== null) return "chinrest-report";
      if (q("input[name=age]")) return "intake";
      if (q(".pen-code")) return "end";
      const h2 = q(".pen-screen h2");
      if (q(".pen-stimuli") && q(".pen-stimuli").style.visibility === "visible") return "trial";
      if (q(".pen-feedback-correct, .pen-feedback-wrong")) return "feedback";
      if (h2 && h2.textContent === "Consent") return "consent";
      if (h2) return "message:" + h2.textContent;
      return "";
    });
    if (!state) continue;
    const trialNumber = state === "trial" ? await page.evaluate(() => screen.trial.number) : -1;
    const name = state === "trial" ? "trial" + trialNumber : state;
    if (name !== lastName) {
      shot += 1;
      await page.screenshot({ path: join(shots, `${String(shot).padStart(2, "0")}-${name.replace(/[^A-Za-z0-9-]+/g, "_").slice(0, 40)}.png`) });
      console.log("screen: " + name);
      if (state === "trial")  // what the trial shows: a frame study's sample above the two
        console.log(name + " images: " + await page.evaluate(() => `sample ${document.querySelectorAll(".pen-sample img").length}, ` +
                                                             `below ${document.querySelectorAll(".pen-stimuli:not(.pen-sample) img").length}`));
      lastName = name;
      changed = Date.now();
    }
    if (state === "consent") await page.keyboard.press("Enter");
    else if (state === "intake") {
      await page.type("input[name=age]", "30");
      await page.select("select[name=vision]", "no");
      await page.click("#jspsych-survey-html-form-next");
    } else if (state === "fullscreen") await page.click("#jspsych-fullscreen-btn");
    else if (state === "chinrest-card") await page.click("#end_resize_phase");
    else if (state === "chinrest-blindspot") {
      for (let i = 0; i < 3; ++i) {
        await page.keyboard.press("Space");
        await sleep(1500);
        await page.keyboard.press("Space");
        await sleep(300);
      }
    } else if (state === "chinrest-report") await page.click("#distance-report #proceed");
    else if (state === "trial" && trialNumber === reloadAt && !reloaded) {
      reloaded = true;
      console.log(`reload on trial ${trialNumber}`);
      await page.reload({ waitUntil: "networkidle0" });
      lastName = "";
    } else if (state === "trial") {
      await page.keyboard.press(answers[trialNumber % answers.length] === "j" ? "j" : "f");
      answered += 1;
      lastName = "";
      changed = Date.now();
    } else if (state.startsWith("message:Connection")) continue;
    else if (state.startsWith("message:")) await page.keyboard.press("Space");
    else if (state === "end") {
      const code = await page.$eval(".pen-code", (e) => e.textContent);
      const text = await page.$eval(".pen-screen .pen-body", (e) => e.innerText.replace(/\n+/g, " / "));
      const link = await page.evaluate(() => { const a = document.querySelector(".pen-screen a"); return a ? a.href : ""; });
      console.log(`end text: ${text}`);
      if (link) console.log(`end link: ${link}`);
      console.log(`end: completion code ${code}, ${answered} trials answered`);
      break;
    }
  }
} finally {
  await browser.close();
}
