// The online study's page (docs/study-online.md). The procedure lives in the server (one
// SessionFlow per participant, as in the lab): this page asks for the current screen, shows it,
// and posts what the participant did, naming the screen it answers (`step`). jsPsych runs the
// parts only a browser can: the intake form, fullscreen, and the virtual chinrest (Li et al. 2020)
// that gives the participant's pixels per degree.
"use strict";

const params = new URLSearchParams(location.search);
// A participant pool's link carries the id (Prolific: PROLIFIC_PID); the server checks it.
const participantId = params.get("id") || params.get("PROLIFIC_PID") || params.get("participant") || "";
// One tab holds an id: its token survives a reload of that tab (sessionStorage), not a new tab.
let tabToken = sessionStorage.getItem("penumbra-tab");
if (!tabToken) {
  tabToken = "t" + Array.from(crypto.getRandomValues(new Uint8Array(12)), (b) => b.toString(16).padStart(2, "0")).join("");
  sessionStorage.setItem("penumbra-tab", tabToken);
}
const pageLoad = "l" + Math.random().toString(16).slice(2, 14);
let eventNumber = 0;
let pageLoadSent = false;  // counted once the session exists

let screen = null;          // the server's last screen
let finished = false;       // the end (or a refusal): the loop stops
let pendingIntake = null;   // posted by the next screen trial (jsPsych's on_finish cannot wait)
let pendingDisplay = null;
let displayProblem = "";
let refreshHz = 0;

async function call(method, path, body) {
  for (let attempt = 0; ; ++attempt) {
    try {
      const response = await fetch(path, {
        method,
        headers: body ? { "Content-Type": "application/json" } : {},
        body: body ? JSON.stringify(body) : undefined,
        cache: "no-store",
      });
      const json = await response.json().catch(() => ({ error: "HTTP " + response.status }));
      return { status: response.status, json };
    } catch (e) {
      // The server is away (a restart): wait and ask again; nothing is lost, the session resumes.
      showMessage("Connection lost", "Reconnecting to the study server…");
      await new Promise((r) => setTimeout(r, Math.min(4000, 250 * (attempt + 1))));
    }
  }
}

async function fetchScreen() {
  const r = await call("GET", `/api/screen?id=${encodeURIComponent(participantId)}&tab=${encodeURIComponent(tabToken)}`);
  if (r.status !== 200) return refuse(r.json.error || "HTTP " + r.status);
  screen = r.json;
}

// Posts an action on the screen on display. A refused post (a stale step after a reload or a
// server restart) reads the screen again; the answer it carried was not recorded.
async function act(action, fields = {}) {
  const r = await call("POST", "/api/act", { id: participantId, tab: tabToken, step: screen.step, action, ...fields });
  if (r.status === 200) {
    screen = r.json;
    return { ok: true };
  }
  if (r.status === 409 || r.status === 404) {
    await fetchScreen();
    return { ok: false, status: r.status, error: r.json.error };
  }
  return { ok: false, status: r.status, error: r.json.error };
}

function refuse(reason) {
  finished = true;
  screen = { screen: "refused", title: "This link cannot be used", body: reason };
}

async function sendEvent(kind) {
  if (!screen || !screen.step) return;
  eventNumber += 1;
  await call("POST", "/api/act", { id: participantId, tab: tabToken, action: "event", kind, load: pageLoad, n: eventNumber });
}
// Neither is counted after the end: the end screen leaves fullscreen itself, and the participant
// then closes the tab (each was counted, so a finished session could show an exit and a switch).
document.addEventListener("visibilitychange", () => {
  if (!finished) sendEvent(document.hidden ? "tab_hidden" : "tab_visible");
});
document.addEventListener("fullscreenchange", () => {
  if (!document.fullscreenElement && !finished) sendEvent("fullscreen_exit");
});

// The refresh rate: the median interval of 60 animation frames.
function estimateRefresh() {
  return new Promise((resolve) => {
    const stamps = [];
    const step = (t) => {
      stamps.push(t);
      if (stamps.length < 61) requestAnimationFrame(step);
      else {
        const d = stamps.slice(1).map((s, i) => s - stamps[i]).sort((a, b) => a - b);
        resolve(1000 / d[Math.floor(d.length / 2)]);
      }
    };
    requestAnimationFrame(step);
  });
}

function element(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

let root = null;  // the jsPsych display element of the screen trial
function showMessage(title, body) {
  const target = root || document.body;
  target.innerHTML = "";
  const s = element("div", "pen-screen");
  s.append(element("h2", "", title), element("div", "pen-body", body));
  target.append(s);
}

function waitKeyOrClick(keys, buttons) {
  return new Promise((resolve) => {
    const onKey = (e) => {
      if (keys[e.key] === undefined) return;
      e.preventDefault();
      done(keys[e.key]);
    };
    const done = (value) => {
      document.removeEventListener("keydown", onKey);
      resolve(value);
    };
    document.addEventListener("keydown", onKey);
    for (const [button, value] of buttons) button.addEventListener("click", () => done(value), { once: true });
  });
}

async function loadImage(url) {
  const img = new Image();
  img.src = url;
  await img.decode();
  return img;
}

function sizedImage(img) {
  const css = screen.stimulus_css_px || screen.stimulus_px;
  img.style.width = img.style.height = css + "px";
  return img;
}

// One trial: the blank for iti_ms, then the stimuli from the frame their first
// requestAnimationFrame callback draws (the onset), every frame's interval until the key press
// (its event timestamp, performance.now's clock).
async function runTrial(display) {
  const trial = screen.trial;
  const images = await Promise.all(trial.images.map(loadImage));
  const s = element("div", "pen-screen");
  const question = element("div", "pen-question", "");
  const gap = (screen.stimulus_css_px || screen.stimulus_px) / 2 + "px";
  const row = element("div", "pen-stimuli");
  row.style.gap = gap;
  row.style.visibility = "hidden";
  images.forEach((img) => row.append(sizedImage(img)));
  // A frame study (match to sample): the reference above the two, half a patch apart, as in the lab.
  const sample = trial.sample ? element("div", "pen-stimuli pen-sample") : null;
  if (sample) {
    sample.style.marginBottom = gap;
    sample.style.visibility = "hidden";
    sample.append(sizedImage(await loadImage(trial.sample)));
    s.append(question, sample, row);
  } else {
    s.append(question, row);
  }
  display.innerHTML = "";
  display.append(s, element("div", "pen-progress", screen.progress || ""));
  const keys = {};
  for (const k of screen.keys.first) keys[k] = "first";
  for (const k of screen.keys.second) keys[k] = "second";
  let hidden = document.hidden;
  const onHidden = () => { if (document.hidden) hidden = true; };
  document.addEventListener("visibilitychange", onHidden);
  const result = await new Promise((resolve) => {
    const blankEnd = performance.now() + trial.iti_ms;
    let last = -1, onset = -1, running = true;
    const frames = [];
    const frame = (t) => {
      if (!running) return;
      if (onset < 0 && t >= blankEnd) {
        row.style.visibility = "visible";  // drawn in this frame: its timestamp is the onset
        if (sample) sample.style.visibility = "visible";
        question.textContent = screen.question;
        onset = t;
        frames.push(last < 0 ? 0 : t - last);
      } else if (onset >= 0) {
        frames.push(t - last);
      }
      last = t;
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
    const onKey = (e) => {
      if (onset < 0 || keys[e.key] === undefined || e.repeat) return;
      e.preventDefault();
      running = false;
      document.removeEventListener("keydown", onKey);
      const at = Math.max(e.timeStamp, onset);
      resolve({ answer: keys[e.key], key: e.key, onset_ms: onset, response_ms: at, rt_ms: at - onset, frame_ms: frames.slice(0, 6000).map((x) => Math.round(x * 100) / 100) });
    };
    document.addEventListener("keydown", onKey);
  });
  document.removeEventListener("visibilitychange", onHidden);
  row.style.visibility = "hidden";
  if (sample) sample.style.visibility = "hidden";
  await act("answer", { trial: trial.number, hidden, fullscreen: !!document.fullscreenElement, ...result });
}

async function runFeedback(display) {
  display.innerHTML = "";
  const s = element("div", "pen-screen");
  s.append(element("div", screen.feedback_correct ? "pen-feedback-correct" : "pen-feedback-wrong", screen.feedback));
  display.append(s, element("div", "pen-progress", screen.progress || ""));
  await new Promise((r) => setTimeout(r, screen.feedback_ms));
  await act("continue");
}

async function runInstructions(display) {
  display.innerHTML = "";
  const s = element("div", "pen-screen");
  s.append(element("h2", "", screen.title), element("div", "pen-body", screen.body));
  if (screen.examples) {
    const ex = element("div", "pen-examples");
    for (const [url, label] of [[screen.examples.jagged, screen.examples.jagged_label], [screen.examples.straight, screen.examples.straight_label]]) {
      const fig = element("figure");
      fig.append(sizedImage(await loadImage(url)), element("figcaption", "", label));
      ex.append(fig);
    }
    s.append(ex);
  }
  if (screen.round_line) s.append(element("div", "", screen.round_line));
  const button = element("button", "jspsych-btn", screen.button.replace(/\s*\(Space\)\s*$/, "") + " (Space)");
  if (screen.button) s.append(button);
  display.append(s, element("div", "pen-progress", screen.progress || ""));
  await waitKeyOrClick({ " ": "continue" }, [[button, "continue"]]);
  await act("continue");
}

async function runConsent(display) {
  display.innerHTML = "";
  const s = element("div", "pen-screen");
  const agree = element("button", "jspsych-btn", screen.first);
  const decline = element("button", "jspsych-btn", screen.second);
  s.append(element("h2", "", screen.title), element("div", "pen-body", screen.body), agree, decline);
  display.append(s);
  const choice = await waitKeyOrClick({ Enter: "agree", Escape: "decline" }, [[agree, "agree"], [decline, "decline"]]);
  await act(choice);
}

// The last screen: the end screen with the completion code, or why the session cannot go on.
function showFinal(display) {
  if (screen.screen !== "end") {
    const titles = { declined: "Thank you", closed: "The session is closed", refused: screen.title };
    root = display;
    showMessage(titles[screen.screen] || "The session is closed",
                screen.body || (screen.screen === "declined" ? "You did not agree; nothing was recorded. You may close this tab." : ""));
    return;
  }
  display.innerHTML = "";
  const s = element("div", "pen-screen");
  s.append(element("h2", "", screen.title), element("div", "pen-body", screen.body));
  if (screen.completion_code) s.append(element("div", "", "Your completion code:"), element("div", "pen-code", screen.completion_code));
  if (screen.completion_url) {
    const a = element("a", "jspsych-btn", "Return to the participant pool");
    a.href = screen.completion_url;
    s.append(a);
  }
  display.append(s);
  if (document.fullscreenElement) document.exitFullscreen().catch(() => {});
}

// The jsPsych trial that shows one server screen and returns when the participant has acted.
class PenumbraScreenPlugin {
  static info = { name: "penumbra-screen", version: "1.0.0", parameters: {}, data: { screen: { type: 0 } } };
  constructor(jsPsych) {
    this.jsPsych = jsPsych;
  }
  async trial(display) {
    root = display;
    if (!screen) await fetchScreen();
    if (screen && screen.step && screen.screen !== "consent" && !pageLoadSent) {
      pageLoadSent = true;
      sendEvent("page_load");
    }
    if (pendingIntake) {
      const answers = pendingIntake;
      pendingIntake = null;
      const r = await act("intake", { answers });
      if (!r.ok && r.status !== 409) displayProblem = r.error;
    }
    if (pendingDisplay) {
      const d = pendingDisplay;
      pendingDisplay = null;
      const r = await act("display", d);
      displayProblem = r.ok ? "" : r.error || "";
    }
    const name = screen.screen;
    if (displayProblem && screen.needs_display) {
      // The server's reason says what to change (a larger window, or sitting farther away).
      showMessage("Your screen cannot show the pictures as they are",
                  displayProblem.charAt(0).toUpperCase() + displayProblem.slice(1) + ".\n\nThen press Space to measure again.");
      displayProblem = "";
      await waitKeyOrClick({ " ": true }, []);
    } else if (screen.needs_display || (screen.needs_intake && name !== "end")) {
      // the loop's intake, fullscreen and chinrest come first
    } else if (needsFullscreen()) {
      // the loop's fullscreen trial comes first
    } else if (name === "consent") await runConsent(display);
    else if (name === "welcome" || name === "round" || name === "break") await runInstructions(display);
    else if (name === "trial") await runTrial(display);
    else if (name === "feedback") await runFeedback(display);
    else finished = true;  // the end, or a refusal: shown once jsPsych has finished (it clears its display)
    root = null;
    this.jsPsych.finishTrial({ screen: name });
  }
}

function needsFullscreen() {
  return !!screen && !!screen.step && !finished && !document.fullscreenElement && !["consent", "end", "declined", "closed", "refused"].includes(screen.screen) &&
    !params.has("no_fullscreen_required");
}

const jsPsych = initJsPsych({});
const intake = {
  type: jsPsychSurveyHtmlForm,
  preamble: "<p>A few questions before we start.</p>",
  html: `<p><label>Age (years) <input name="age" type="number" min="16" max="120" required></label></p>
         <p><label>Do you wear glasses or contact lenses for this distance?
           <select name="vision" required><option value="">choose</option><option>no</option><option>glasses</option><option>contact lenses</option></select></label></p>`,
  button_label: "Continue",
  on_finish: (data) => { pendingIntake = Object.fromEntries(Object.entries(data.response).map(([k, v]) => [k, String(v)])); },
};
const fullscreen = {
  type: jsPsychFullscreen,
  fullscreen_mode: true,
  message: "<p>The study runs in fullscreen. If you leave fullscreen, you will be asked to return.</p>",
  button_label: "Enter fullscreen",
};
// The chinrest's blind-spot readings one by one (the plugin keeps only their mean): the ball's and
// the square's centres at every press of Space that stops the ball (presses alternate: start,
// stop), read before the plugin's own listener moves anything. A redo draws a new ball and starts
// the readings afresh, as the plugin does.
const kBlindSpotAngleDeg = 13.5;  // the plugin's angle between fixation and the blind spot
let blindSpot = { ball: null, presses: 0, offsets_px: [] };
function onBlindSpotKey(e) {
  if (e.key !== " " || e.repeat) return;
  const ball = document.querySelector("#virtual-chinrest-circle");
  const square = document.querySelector("#virtual-chinrest-square");
  if (!ball || !square) return;
  if (ball !== blindSpot.ball) blindSpot = { ball, presses: 0, offsets_px: [] };
  blindSpot.presses += 1;
  if (blindSpot.presses % 2 === 1) return;  // this press starts the ball
  const centre = (el) => { const b = el.getBoundingClientRect(); return b.left + b.width / 2; };
  blindSpot.offsets_px.push(centre(square) - centre(ball));
}

const chinrest = {
  type: jsPsychVirtualChinrest,
  blindspot_reps: 3,
  resize_units: "none",
  on_load: () => {
    blindSpot = { ball: null, presses: 0, offsets_px: [] };
    window.addEventListener("keydown", onBlindSpotKey, true);
  },
  on_finish: async (data) => {
    window.removeEventListener("keydown", onBlindSpotKey, true);
    const distances = blindSpot.offsets_px.map((px) => px / data.px2mm / Math.tan(kBlindSpotAngleDeg * Math.PI / 180));
    pendingDisplay = {
      px_per_mm: data.px2mm,
      viewing_distance_mm: data.view_dist_mm,
      window_width_css_px: window.innerWidth,
      window_height_css_px: window.innerHeight,
      screen_width_css_px: screen_width(),
      screen_height_css_px: screen_height(),
      device_pixel_ratio: window.devicePixelRatio,
      refresh_hz: refreshHz,
      user_agent: navigator.userAgent.slice(0, 400),
      chinrest: { item_width_px: data.item_width_px, item_width_mm: data.item_width_mm, px2mm: data.px2mm, view_dist_mm: data.view_dist_mm,
                  blindspot_distances_mm: distances.map((d) => Math.round(d * 100) / 100) },
    };
  },
};
function screen_width() { return window.screen.width; }
function screen_height() { return window.screen.height; }

const loop = {
  timeline: [
    { timeline: [intake], conditional_function: () => !!screen && !finished && screen.needs_intake === true },
    { timeline: [fullscreen], conditional_function: needsFullscreen },
    { timeline: [chinrest], conditional_function: () => !!screen && !finished && screen.needs_display === true },
    { type: PenumbraScreenPlugin },
  ],
  loop_function: () => !finished,
};

(async () => {
  if (!participantId) refuse("The link has no participant id (…/?id=YOUR_ID).");
  refreshHz = await estimateRefresh();
  await jsPsych.run([loop]);
  showFinal(jsPsych.getDisplayElement());
})();
