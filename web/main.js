// The ChopperScape page: runs the Rust game (compiled to WebAssembly) at 30 steps per second and draws each
// frame straight from WebAssembly memory into the canvas.
import init, { Game, mode_names, mode_value } from "./pkg/chopperscape_web.js";

const STEP_MS = 1000 / 30; // SPEC: render_fps = 30
const MAX_STEPS_PER_FRAME = 5; // after a stall (hidden tab), catch up a little, never in a burst
const WIDTH = 800;
const HEIGHT = 600;
const NOOP = 4;
// Held direction keys map to actions: 0 Right, 1 Left, 2 Down, 3 Up.
const DIRECTIONS = {
  ArrowRight: 0, KeyD: 0,
  ArrowLeft: 1, KeyA: 1,
  ArrowDown: 2, KeyS: 2,
  ArrowUp: 3, KeyW: 3,
};
const CAUSES = { bird: "Hit by a bird", fuel: "Out of fuel" };
// The trained agents, exported by `python -m chopperscape.learn.export` and served beside the page: the features
// MLP (`models/ppo-features.pt`) and the pixel CNN (`models/ppo-pixels.pt`, trained on frames alone, which flies on
// the 42 × 42 agent-view frames it learned). The "Agent" menu picks one.
const AGENT_URLS = { features: "models/ppo-features.onnx", pixels: "models/ppo-pixels.onnx" };

const $ = (id) => document.getElementById(id);
const canvas = $("screen");
const ctx = canvas.getContext("2d", { alpha: false });

const wasm = await init();
// The rules the form sets beside the mode; a mode fixes them (the core's modes table, as `--mode` does).
const RULE_INPUTS = ["lives", "alien_prob"];
for (const name of mode_names()) $("mode").add(new Option(name, name));

// A mode fills the rules inputs with its values and locks them; "custom" unlocks them.
function applyMode() {
  const mode = $("mode").value;
  for (const name of RULE_INPUTS) {
    if (mode) $(name).value = mode_value(mode, name);
    $(name).disabled = Boolean(mode);
  }
}

let game = null;
let seed = 0n; // of the game on screen
let over = false;
let paused = false;
let heuristic = false;
let agent = false; // the trained policy flies (its game was made with Game.with_policy)
const agentBytes = new Map(); // each policy file, fetched once (by URL)
let lastCause = null;
let held = []; // codes of held direction keys, the last pressed last: it wins
let acc = 0;
let last = null;

function draw() {
  // A view, not a copy: the pixels live in WebAssembly memory. Views are remade each frame because
  // memory.buffer changes when the memory grows.
  const pixels = new Uint8ClampedArray(wasm.memory.buffer, game.frame_ptr(), game.frame_len());
  ctx.putImageData(new ImageData(pixels, WIDTH, HEIGHT), 0, 0);
}

function showError(text) {
  $("error").textContent = text;
  $("error").hidden = !text;
}

function readSeed() {
  const text = $("seed").value.trim();
  if (!/^\d+$/.test(text) || BigInt(text) >= 2n ** 64n) {
    throw new Error(`invalid seed \`${text}\`: allowed an integer in 0..=18446744073709551615`);
  }
  return BigInt(text);
}

// R restarts with the next seed, as `chopperscape play` does.
function restartWithNextSeed() {
  const typed = $("seed").value;
  $("seed").value = String((seed + 1n) % 2n ** 64n);
  const error = newGame();
  if (error) $("seed").value = typed;
  return error;
}

// Starts a game from the form. Returns the error message, or null. A bad form changes nothing.
function newGame() {
  let next;
  let nextSeed;
  try {
    nextSeed = readSeed();
    const names = ["mode", ...RULE_INPUTS];
    const values = names.map((name) => $(name).value);
    next = agent ? Game.with_policy(agentBytes.get(agentUrl()), names, values) : new Game(names, values);
  } catch (e) {
    showError(e.message);
    return e.message;
  }
  showError("");
  game?.free();
  game = next;
  seed = nextSeed;
  game.reset(seed);
  over = false;
  lastCause = null;
  acc = 0;
  $("message").hidden = true;
  draw();
  updateStatus();
  return null;
}

function action() {
  if (agent) return game.agent_action();
  if (heuristic) return game.heuristic_action();
  return held.length ? DIRECTIONS[held[held.length - 1]] : NOOP;
}

function stepOnce(a) {
  const r = game.step(a);
  const result = { reward: r.reward, terminated: r.terminated, truncated: r.truncated, cause: r.cause ?? null };
  r.free();
  if (result.terminated || result.truncated) endEpisode(result);
  return result;
}

function endEpisode(result) {
  over = true;
  lastCause = result.terminated ? result.cause : "truncated";
  $("message-title").textContent = result.terminated ? CAUSES[result.cause] : "Time's up";
  $("message-detail").textContent = `Return ${game.episode_return()} after ${game.steps()} steps`;
  $("message").hidden = false;
}

function setPaused(on) {
  paused = on;
  $("pause").setAttribute("aria-pressed", String(on));
  $("pause").textContent = on ? "Resume" : "Pause";
  $("paused").hidden = !on || over;
  updateStatus();
}

function setHeuristic(on) {
  if (on && agent) setAgentOff();
  heuristic = on;
  $("heuristic").setAttribute("aria-pressed", String(on));
  if (on && over) newGame();
  updateStatus();
}

// The URL of the policy the "Agent" menu picks.
function agentUrl() {
  return AGENT_URLS[$("agent-model").value] ?? AGENT_URLS.features;
}

// Fetches the chosen trained policy (once). Returns the error message, or null.
async function loadAgent() {
  const url = agentUrl();
  if (agentBytes.has(url)) return null;
  try {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText || "error"}`);
    agentBytes.set(url, new Uint8Array(await response.arrayBuffer()));
    return null;
  } catch (e) {
    return `${e.message}`;
  }
}

function setAgentOff() {
  agent = false;
  $("agent").setAttribute("aria-pressed", "false");
}

// Lets the trained agent fly a new game with the form's seed and options, or hands the game back. Returns the
// error message (also shown on the page), or null; on an error the game on screen goes on unchanged.
async function setAgent(on) {
  if (!on) {
    setAgentOff();
    newGame();
    return null;
  }
  const failed = await loadAgent();
  if (failed) {
    const message = `The trained agent could not be loaded: ${failed}`;
    showError(message);
    return message;
  }
  if (heuristic) setHeuristic(false);
  agent = true;
  const error = newGame();
  if (error) {
    setAgentOff();
    agentBytes.delete(agentUrl()); // a bad file is fetched again next time
    const message = `The trained agent could not be loaded: ${error}`;
    showError(message);
    return message;
  }
  $("agent").setAttribute("aria-pressed", "true");
  return null;
}

function updateStatus() {
  const who = agent ? "The trained agent is flying" : heuristic ? "The heuristic is flying" : "You are flying";
  const state = over ? "episode over" : paused ? "paused" : `step ${game.steps()}`;
  $("status").textContent = `${who} · ${state}`;
}

function frame(now) {
  if (last !== null) acc += now - last;
  last = now;
  if (!game || over || paused) acc = 0;
  let steps = 0;
  while (acc >= STEP_MS && !over) {
    if (steps === MAX_STEPS_PER_FRAME) {
      acc = 0;
      break;
    }
    acc -= STEP_MS;
    stepOnce(action());
    steps += 1;
  }
  if (steps) {
    draw();
    updateStatus();
  }
  requestAnimationFrame(frame);
}

function isTyping(event) {
  return event.target instanceof HTMLInputElement;
}

window.addEventListener("keydown", (event) => {
  if (isTyping(event) || event.ctrlKey || event.metaKey || event.altKey) return;
  if (event.code in DIRECTIONS) {
    event.preventDefault();
    held = held.filter((c) => c !== event.code);
    held.push(event.code);
  } else if (event.code === "KeyP" && !event.repeat) {
    setPaused(!paused);
  } else if (event.code === "KeyR" && !event.repeat) {
    restartWithNextSeed();
  }
});
window.addEventListener("keyup", (event) => {
  held = held.filter((c) => c !== event.code);
});
window.addEventListener("blur", () => {
  held = [];
});

$("controls").addEventListener("submit", (event) => {
  event.preventDefault();
  if (newGame() === null) canvas.focus();
});
$("mode").addEventListener("change", applyMode);
$("pause").addEventListener("click", () => setPaused(!paused));
$("heuristic").addEventListener("click", () => setHeuristic(!heuristic));
$("agent").addEventListener("click", () => setAgent(!agent));
// Another agent while one flies: it takes over a new game with the same seed and options.
$("agent-model").addEventListener("change", () => agent && setAgent(true));

function base64(bytes) {
  let text = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(text);
}

// A small hook for the browser tests: read the state and the frame, and step by hand.
window.chopperscape = {
  state: () => ({
    x: game.chopper_x(),
    y: game.chopper_y(),
    fuel: game.fuel(),
    lives: game.lives(),
    score: game.episode_return(),
    steps: game.steps(),
    seed: String(seed),
    over,
    cause: lastCause,
    paused,
    heuristic,
    agent,
  }),
  // Fills the form and starts a game; returns the error message, or null.
  newGame(seedValue, options = {}) {
    $("seed").value = String(seedValue);
    $("mode").value = options.mode ?? "";
    applyMode();
    if (!options.mode) {
      $("lives").value = String(options.lives ?? 1);
      $("alien_prob").value = String(options.alien_prob ?? 0);
    }
    return newGame();
  },
  setPaused,
  setHeuristic,
  setAgent,
  // The action the flyer on screen (the trained agent, the heuristic, or no key: Do Nothing) picks now.
  action: () => action(),
  // Steps these actions now (paused or not), stopping if the episode ends; then draws.
  stepN(actions) {
    for (const a of actions) {
      if (over) break;
      stepOnce(a);
    }
    draw();
    updateStatus();
    return this.state();
  },
  // Steps with the flyer on screen until the episode ends (or `limit` steps); then draws.
  playToEnd(limit = 20000) {
    for (let i = 0; i < limit && !over; i++) stepOnce(action());
    draw();
    updateStatus();
    return this.state();
  },
  // The frame as the canvas shows it, RGB, base64.
  frameBytes() {
    const rgba = ctx.getImageData(0, 0, WIDTH, HEIGHT).data;
    const rgb = new Uint8Array(WIDTH * HEIGHT * 3);
    for (let i = 0, j = 0; i < rgba.length; i += 4, j += 3) {
      rgb[j] = rgba[i];
      rgb[j + 1] = rgba[i + 1];
      rgb[j + 2] = rgba[i + 2];
    }
    return base64(rgb);
  },
  // The RGB frame in WebAssembly memory, base64.
  wasmFrameBytes: () => base64(new Uint8Array(wasm.memory.buffer, game.rgb_ptr(), game.rgb_len())),
};

newGame();
canvas.focus();
requestAnimationFrame(frame);
window.chopperscape.ready = true;
