// nmmm 2AFC experiment: participant page.
// The server holds the trial order and the placement of the photograph; this page only
// shows what it is given and sends back the chosen screen position and the response time.
// Unacknowledged responses are kept in localStorage and re-sent with the same response id
// (the server stores each response exactly once), so a server restart or a reload loses nothing.
// Both images of a trial arrive in ONE response of raw, uncompressed sRGB bytes (same length
// whichever side holds the photograph) and are drawn into canvases here: nothing but the
// pixels differs between the two sides.
"use strict";

const KEY_SESSION = "nmmm.experiment.session";
const KEY_PENDING = "nmmm.experiment.pending";
const KEY_CLIENT = "nmmm.experiment.client";   // {participant_id, token}: resumes a creation whose reply was lost
const $ = (id) => document.getElementById(id);

const state = { config: null, session: null, trial: null, shownAt: null, accepting: false, images: {} };

function show(name) {
  for (const s of document.querySelectorAll(".screen")) s.classList.toggle("active", s.id === "screen-" + name);
}
function setError(msg) { $("error").textContent = msg || ""; }
function setStatus(msg) { $("status").textContent = msg || ""; }
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

function uuid4() {
  if (window.crypto && crypto.randomUUID) return crypto.randomUUID();
  const b = crypto.getRandomValues(new Uint8Array(16));
  b[6] = (b[6] & 0x0f) | 0x40; b[8] = (b[8] & 0x3f) | 0x80;
  const h = Array.from(b, (x) => x.toString(16).padStart(2, "0")).join("");
  return `${h.slice(0, 8)}-${h.slice(8, 12)}-${h.slice(12, 16)}-${h.slice(16, 20)}-${h.slice(20)}`;
}

// fetch JSON; network failures and 5xx are retried (the server may be restarting)
async function api(path, options = {}, { retry = true } = {}) {
  let delay = 100;
  for (;;) {
    let resp;
    try {
      resp = await fetch(path, { cache: "no-store", ...options });
    } catch (e) {
      resp = null;
    }
    if (resp && resp.status < 500) {
      setStatus("");
      let body = {};
      try { body = await resp.json(); } catch (e) { body = {}; }
      return { status: resp.status, body };
    }
    if (!retry) throw new Error("server unavailable");
    let why = "Connection to the server lost";
    if (resp) {   // 503: the server cannot store now (its message says why); nothing was stored
      try { why = (await resp.json()).error || why; } catch (e) { why = `Server error ${resp.status}`; }
    }
    setStatus(why + " — retrying…");
    await sleep(delay);
    delay = Math.min(delay * 2, 1000);
  }
}

function postJSON(path, payload) {
  return api(path, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(payload) });
}

async function init() {
  const params = new URLSearchParams(location.search);
  if (params.get("session")) {
    localStorage.setItem(KEY_SESSION, params.get("session"));
    history.replaceState(null, "", "/");
  }
  const cfg = await api("/api/config");
  state.config = cfg.body;
  const c = state.config;
  document.title = c.title;
  document.documentElement.style.setProperty("--bg", c.background);
  document.documentElement.style.setProperty("--frame", c.frame_px + "px");
  $("title").textContent = c.title;
  $("consent-text").textContent = c.consent_text;
  $("calibration-note").textContent = c.calibration_note;
  $("question").textContent = c.question;
  $("ready-question").textContent = c.question;
  $("ready-keys").textContent = c.stereo ? "↑ or ↓" : "← or →";

  state.session = localStorage.getItem(KEY_SESSION);
  if (state.session) {
    await flushPending();
    const r = await api(`/api/session/${state.session}`);
    if (r.status === 200) return showReady(r.body);
    localStorage.removeItem(KEY_SESSION);
    localStorage.removeItem(KEY_PENDING);
    state.session = null;
  }
  show("consent");
}

function showReady(progress) {
  if (progress.done) return show("done");
  $("ready-heading").textContent = progress.answered > 0 ? "Welcome back" : "Instructions";
  $("ready-progress").textContent = progress.answered > 0
    ? `You have answered ${progress.answered} of ${progress.n_trials} trials; the session continues where you stopped.`
    : `There are ${progress.n_trials} trials.`;
  show("ready");
  $("begin").focus();
}

async function start(event) {
  event.preventDefault();
  setError("");
  const pid = $("participant-id").value.trim();
  if (!$("consent").checked) return setError("Please tick the consent box to take part.");
  // a random token sent with the id: if the reply is lost (server crash), the retry resumes
  let client = null;
  try { client = JSON.parse(localStorage.getItem(KEY_CLIENT) || "null"); } catch (e) { client = null; }
  if (!client || client.participant_id !== pid) {
    client = { participant_id: pid, token: uuid4().replace(/-/g, "") };
    localStorage.setItem(KEY_CLIENT, JSON.stringify(client));
  }
  const r = await postJSON("/api/participants", {
    participant_id: pid, consent: true, client_token: client.token,
    screen: { width: screen.width, height: screen.height, dpr: window.devicePixelRatio },
  });
  if (r.status !== 201 && r.status !== 200) return setError(r.body.error || `error ${r.status}`);
  state.session = r.body.session;
  localStorage.setItem(KEY_SESSION, state.session);
  showReady(r.body);
}

// one view of raw sRGB bytes (rows top to bottom) -> a canvas of width x height pixels
function rgbCanvas(bytes, width, height) {
  const canvas = document.createElement("canvas");
  canvas.width = width;
  canvas.height = height;
  const ctx = canvas.getContext("2d");
  const img = ctx.createImageData(width, height);
  const out = img.data;
  for (let i = 0, j = 0; i < bytes.length; i += 3, j += 4) {
    out[j] = bytes[i]; out[j + 1] = bytes[i + 1]; out[j + 2] = bytes[i + 2]; out[j + 3] = 255;
  }
  ctx.putImageData(img, 0, 0);
  return canvas;
}

// one image pixel per device pixel (a calibrated display shows the rendering's detail as
// computed); both images share one pixel size, so CSS limits scale them alike if too large
function deviceExact(canvas) {
  const dpr = window.devicePixelRatio || 1;
  canvas.style.width = canvas.width / dpr + "px";
  canvas.style.height = "auto";
  return canvas;
}

function buildStage(trial, imgs) {
  const stage = $("stage");
  stage.replaceChildren();
  stage.classList.toggle("stereo", !!state.config.stereo);
  for (const slot of state.config.slots) {
    const frame = document.createElement("div");
    frame.className = "frame";
    frame.dataset.slot = slot;
    frame.id = "choice-" + slot;
    frame.tabIndex = 0;
    if (state.config.stereo) {
      const eyes = state.config.stereo_arrangement === "cross" ? ["right_eye", "left_eye"] : ["left_eye", "right_eye"];
      for (const eye of eyes) frame.appendChild(deviceExact(imgs[slot][eye]));
    } else {
      frame.appendChild(deviceExact(imgs[slot]));
    }
    frame.addEventListener("click", () => respond(slot));
    stage.appendChild(frame);
  }
}

// every view of the trial in one response: raw RGB, views in trial.stimuli.views order
async function fetchImages(trial) {
  const spec = trial.stimuli;
  const resp = await fetch(spec.url, { cache: "no-store" });
  if (!resp.ok) throw new Error(`stimuli: error ${resp.status}`);
  const buf = new Uint8Array(await resp.arrayBuffer());
  if (buf.length !== spec.bytes) throw new Error(`stimuli: ${buf.length} bytes, expected ${spec.bytes}`);
  const n = 3 * trial.width * trial.height;
  const out = {};
  spec.views.forEach(([slot, eye], k) => {
    const canvas = rgbCanvas(buf.subarray(k * n, (k + 1) * n), trial.width, trial.height);
    if (eye) (out[slot] = out[slot] || {})[eye] = canvas;
    else out[slot] = canvas;
  });
  return out;
}

async function nextTrial() {
  state.accepting = false;
  document.body.dataset.phase = "blank";
  $("stage").classList.remove("shown");
  show("trial");
  const blank = sleep(state.config.blank_ms);     // neutral blank interval
  let r = await api(`/api/session/${state.session}/trial`);
  if (r.status === 404) { localStorage.removeItem(KEY_SESSION); return location.reload(); }
  if (r.body.done) return show("done");
  const trial = r.body;
  let imgs;
  for (;;) {
    try { imgs = await fetchImages(trial); break; }
    catch (e) { setStatus("Loading images failed — retrying…"); await sleep(500); }
  }
  setStatus("");
  await blank;
  state.trial = trial;
  buildStage(trial, imgs);
  $("counter").textContent = `${trial.answered + 1} / ${trial.n_trials}`;
  $("stage").classList.add("shown");     // both images appear in the same frame
  requestAnimationFrame(() => {
    state.shownAt = performance.now();
    state.accepting = true;
    document.body.dataset.phase = "awaiting-response";
  });
}

async function respond(slot) {
  if (!state.accepting) return;
  state.accepting = false;
  const rt = performance.now() - state.shownAt;
  document.body.dataset.phase = "sending";
  $("stage").classList.remove("shown");
  const pending = {
    session: state.session, response_id: uuid4(), trial_index: state.trial.trial_index,
    choice: slot, rt_ms: Math.round(rt * 10) / 10,
  };
  localStorage.setItem(KEY_PENDING, JSON.stringify(pending));
  const ack = await submit(pending);
  if (ack && ack.done) return show("done");
  nextTrial();
}

async function submit(p) {
  const { session, ...payload } = p;
  const r = await postJSON(`/api/session/${session}/responses`, payload);
  localStorage.removeItem(KEY_PENDING);
  if (r.status === 201 || r.status === 200) return r.body;
  if (r.status !== 409) setError(r.body.error || `error ${r.status}`);
  return null;   // 409: already answered or out of order; the server's next trial is the truth
}

async function flushPending() {
  const raw = localStorage.getItem(KEY_PENDING);
  if (!raw) return;
  try {
    const p = JSON.parse(raw);
    if (p.session === state.session) await submit(p);
    else localStorage.removeItem(KEY_PENDING);
  } catch (e) {
    localStorage.removeItem(KEY_PENDING);
  }
}

document.addEventListener("keydown", (e) => {
  if (!state.accepting || !state.config) return;
  const keys = state.config.stereo ? { ArrowUp: "top", ArrowDown: "bottom" } : { ArrowLeft: "left", ArrowRight: "right" };
  if (keys[e.key]) { e.preventDefault(); respond(keys[e.key]); }
});

document.addEventListener("DOMContentLoaded", () => {
  $("consent-form").addEventListener("submit", start);
  $("begin").addEventListener("click", () => { setError(""); nextTrial(); });
  init().catch((e) => setError(String(e)));
});
