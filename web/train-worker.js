// The Train control's worker: the Rust learner (crates/learn, the `fast` recipe, compiled to wasm) learning in a
// Web Worker, so that the page never waits for it. Messages in: {type: "start", seed, numEnvs, numSteps,
// totalSteps, evalEvery} (a fresh run the first time, then it goes on), {type: "stop"}, {type: "onnx"}. Out:
// {type: "row", row (a progress.csv line), envSteps, onnx (the current policy), decisionsPerSec}, {type: "eval",
// envSteps, mean} (the greedy policy on EVAL_EPISODES held-out episodes, every `evalEvery` updates and at the end),
// {type: "heuristic", mean} (the heuristic on the same episodes, once), {type: "onnx", bytes}, {type: "stopped"}
// (the answer to "stop": no update starts after it, and every row learned before it was posted before it),
// {type: "finished"}, {type: "error", message}.
import init, { Trainer } from "./pkg/chopperscape_web.js";

// The held-out episodes of the evaluation: seeds 1,000,000 to 1,000,019 (Python's `evaluate` plays its first 20).
const EVAL_EPISODES = 20;
const EVAL_SEED = 1000000;

const ready = init();
let trainer = null;
let evalEvery = 10;
let updates = 0;
let running = false;
// The current loop's number: a "stop" or a newer "start" changes it, and a loop whose number is no longer `run` ends
// at its next check, so that a "stop" and a "start" arriving while a loop waits leave one loop running, never two.
let run = 0;
let wall = 0; // seconds spent learning (stopped time not counted)

function post(message, transfer = []) {
  self.postMessage(message, transfer);
}

// Posts the greedy policy's evaluation; if it fails, posts the error and stops the run (returns false).
function evaluate() {
  try {
    post({ type: "eval", envSteps: trainer.env_steps(), mean: trainer.evaluate(EVAL_EPISODES, EVAL_SEED) });
    return true;
  } catch (err) {
    running = false;
    post({ type: "error", message: String(err) });
    return false;
  }
}

async function loop(mine) {
  while (mine === run) {
    if (trainer.finished()) {
      running = false;
      if (updates % evalEvery !== 0) evaluate();
      post({ type: "finished" });
      return;
    }
    const t0 = performance.now();
    const before = trainer.env_steps();
    let row;
    try {
      row = trainer.update(wall);
    } catch (err) {
      running = false;
      post({ type: "error", message: String(err) });
      return;
    }
    const seconds = (performance.now() - t0) / 1000;
    wall += seconds;
    const envSteps = trainer.env_steps();
    const onnx = trainer.onnx();
    post({ type: "row", row, envSteps, onnx, decisionsPerSec: (envSteps - before) / seconds }, [onnx.buffer]);
    updates += 1;
    if (updates % evalEvery === 0 && !evaluate()) return;
    // Let a "stop" message in between updates.
    await new Promise((ok) => setTimeout(ok, 0));
  }
}

self.onmessage = async (event) => {
  const m = event.data;
  await ready;
  try {
    if (m.type === "start") {
      if (!trainer) {
        trainer = new Trainer(m.seed ?? 0, m.numEnvs ?? 0, m.numSteps ?? 0, m.totalSteps ?? 0);
        evalEvery = m.evalEvery > 0 ? m.evalEvery : 10;
        post({ type: "header", header: Trainer.csv_header() });
        post({ type: "heuristic", mean: trainer.heuristic(EVAL_EPISODES, EVAL_SEED) });
      }
      if (!running) {
        running = true;
        run += 1;
        loop(run);
      }
    } else if (m.type === "stop") {
      running = false;
      run += 1;
      post({ type: "stopped" });
    } else if (m.type === "onnx" && trainer) {
      const bytes = trainer.onnx();
      post({ type: "onnx", bytes }, [bytes.buffer]);
    }
  } catch (err) {
    post({ type: "error", message: String(err) });
  }
};
