// "Learn in your browser": the Train control. The learner runs in a Web Worker (train-worker.js); this module
// draws its learning curve as it grows (the mean return of the last 100 training episodes against decisions, and
// the greedy policy's held-out evaluation every few updates beside the heuristic's on the same episodes), flies the
// current policy beside it (a Game made with Game.with_policy from the worker's latest ONNX, swapped in at each
// episode's end), and downloads the policy as ONNX at any time. `window.chopperscapeTrain` exposes the state the
// browser test reads.
import init, { Game } from "./pkg/chopperscape_web.js";

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
// A smaller batch for tests (`?train_envs=8&train_steps=64&train_eval_every=3`); the preset's 128 × 128 otherwise,
// evaluated every 10 updates.
const numEnvs = Number(params.get("train_envs") ?? 0);
const numSteps = Number(params.get("train_steps") ?? 0);
const evalEvery = Number(params.get("train_eval_every") ?? 0);

// `evals`: {envSteps, mean} of the greedy policy on the held-out episodes; `heuristic`: the heuristic's mean on
// the same episodes; `passedAt`: seconds from the first click to the first evaluation above it; `stoppedRows`: the
// rows received when the worker answered the last Stop (null while it runs or before it answers): no row follows.
const state = {
  rows: [],
  evals: [],
  heuristic: null,
  policies: 0,
  flownPolicy: 0,
  running: false,
  decisionsPerSec: 0,
  started: null,
  passedAt: null,
  stoppedRows: null,
};
window.chopperscapeTrain = state;
let worker = null;
let latest = null; // the newest policy's ONNX bytes
let game = null;
let seed = 1000000;
let wasm = null;
let header = [];

function column(name, fields) {
  const i = header.indexOf(name);
  return i < 0 || fields[i] === "" ? null : Number(fields[i]);
}

function drawCurve() {
  const canvas = $("curve");
  const ctx = canvas.getContext("2d");
  const { width, height } = canvas;
  ctx.clearRect(0, 0, width, height);
  const points = state.rows.filter((r) => r.meanReturn !== null);
  const maxX = Math.max(1, ...state.rows.map((r) => r.envSteps));
  const bar = state.heuristic ?? 0;
  const maxY = Math.max(bar * 1.2, 1000, ...points.map((r) => r.meanReturn), ...state.evals.map((e) => e.mean));
  const x = (v) => 30 + (v / maxX) * (width - 40);
  const y = (v) => height - 20 - (v / maxY) * (height - 30);
  ctx.strokeStyle = "#999";
  ctx.setLineDash([4, 4]);
  ctx.beginPath();
  if (state.heuristic !== null) {
    ctx.moveTo(x(0), y(bar));
    ctx.lineTo(x(maxX), y(bar));
  }
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.fillStyle = "#666";
  ctx.font = "11px sans-serif";
  if (state.heuristic !== null) ctx.fillText("heuristic (held out)", x(0) + 2, y(bar) - 3);
  ctx.fillText(`${maxX.toLocaleString()} decisions`, width - 120, height - 5);
  ctx.strokeStyle = "#c0392b";
  ctx.lineWidth = 2;
  ctx.beginPath();
  points.forEach((r, i) => (i ? ctx.lineTo(x(r.envSteps), y(r.meanReturn)) : ctx.moveTo(x(r.envSteps), y(r.meanReturn))));
  ctx.stroke();
  ctx.lineWidth = 1;
  // The greedy policy on the held-out episodes: blue points.
  ctx.fillStyle = "#2e6fd8";
  for (const e of state.evals) {
    ctx.beginPath();
    ctx.arc(x(e.envSteps), y(e.mean), 3.5, 0, 2 * Math.PI);
    ctx.fill();
  }
}

function status() {
  const last = state.rows.at(-1);
  const ret = last?.meanReturn == null ? "–" : Math.round(last.meanReturn).toLocaleString();
  const held = state.evals.at(-1);
  const evalText = held ? ` · greedy ${Math.round(held.mean).toLocaleString()} held out` : "";
  const passed = state.passedAt === null ? "" : ` · passed the heuristic at ${Math.round(state.passedAt)} s`;
  $("train-status").textContent = state.rows.length
    ? `${last.envSteps.toLocaleString()} decisions · return ${ret} (last 100 episodes)${evalText} · ` +
      `${Math.round(state.decisionsPerSec).toLocaleString()} decisions/s${passed}${state.running ? "" : " · stopped"}`
    : state.running ? "starting…" : "Train an agent here, on your machine: PPO in Rust, compiled to WebAssembly.";
}

function newFlight() {
  if (!latest) return;
  game = Game.with_policy(latest, [], []);
  game.reset(BigInt(seed++));
  state.flownPolicy = state.policies;
}

function fly() {
  if (game) {
    if (game.is_over()) newFlight();
    else game.step(game.agent_action());
    const pixels = new Uint8ClampedArray(wasm.memory.buffer, game.frame_ptr(), game.frame_len());
    const off = new OffscreenCanvas(800, 600);
    off.getContext("2d").putImageData(new ImageData(pixels.slice(), 800, 600), 0, 0);
    const ctx = $("learner-screen").getContext("2d");
    ctx.drawImage(off, 0, 0, 400, 300);
  }
  setTimeout(fly, 1000 / 30);
}

function onMessage(event) {
  const m = event.data;
  if (m.type === "header") header = m.header.split(",");
  else if (m.type === "row") {
    const fields = m.row.split(",");
    state.rows.push({ envSteps: m.envSteps, meanReturn: column("mean_return", fields), line: m.row });
    state.decisionsPerSec = m.decisionsPerSec;
    state.policies += 1;
    latest = m.onnx;
    if (!game) newFlight();
    drawCurve();
    status();
  } else if (m.type === "heuristic") {
    state.heuristic = m.mean;
    drawCurve();
  } else if (m.type === "eval") {
    state.evals.push({ envSteps: m.envSteps, mean: m.mean });
    if (state.passedAt === null && state.heuristic !== null && m.mean > state.heuristic) {
      state.passedAt = (performance.now() - state.started) / 1000;
    }
    drawCurve();
    status();
  } else if (m.type === "onnx") {
    const url = URL.createObjectURL(new Blob([m.bytes], { type: "application/octet-stream" }));
    const a = document.createElement("a");
    a.href = url;
    a.download = "chopperscape-fast.onnx";
    a.click();
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  } else if (m.type === "stopped") {
    // Rows the worker posted before it read the Stop arrive before this answer; none come after it.
    if (!state.running) state.stoppedRows = state.rows.length;
  } else if (m.type === "finished") {
    setRunning(false);
  } else if (m.type === "error") {
    setRunning(false);
    $("train-status").textContent = `error: ${m.message}`;
  }
}

function setRunning(on) {
  state.running = on;
  $("train").textContent = on ? "Stop" : state.rows.length ? "Resume" : "Train";
  $("train").setAttribute("aria-pressed", String(on));
  $("download").disabled = !state.rows.length;
  status();
}

$("train").addEventListener("click", () => {
  if (!worker) {
    worker = new Worker("train-worker.js", { type: "module" });
    worker.onmessage = onMessage;
    worker.onerror = (e) => onMessage({ data: { type: "error", message: e.message } });
    state.started = performance.now();
  }
  const on = !state.running;
  state.stoppedRows = null;
  worker.postMessage(on ? { type: "start", seed: 0, numEnvs, numSteps, evalEvery } : { type: "stop" });
  setRunning(on);
});
$("download").addEventListener("click", () => worker?.postMessage({ type: "onnx" }));

wasm = await init();
setRunning(false);
drawCurve();
fly();
