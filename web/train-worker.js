// The Train control's worker: the Rust learner (crates/learn, the `fast` recipe, compiled to wasm) learning in a
// Web Worker, so that the page never waits for it. Messages in: {type: "start", seed, numEnvs, numSteps,
// totalSteps} (a fresh run the first time, then it goes on), {type: "stop"}, {type: "onnx"}. Out: {type: "row",
// row (a progress.csv line), envSteps, onnx (the current policy), decisionsPerSec}, {type: "onnx", bytes},
// {type: "finished"}, {type: "error", message}.
import init, { Trainer } from "./pkg/chopperscape_web.js";

const ready = init();
let trainer = null;
let running = false;
let wall = 0; // seconds spent learning (stopped time not counted)

function post(message, transfer = []) {
  self.postMessage(message, transfer);
}

async function loop() {
  while (running) {
    if (trainer.finished()) {
      running = false;
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
        post({ type: "header", header: Trainer.csv_header() });
      }
      if (!running) {
        running = true;
        loop();
      }
    } else if (m.type === "stop") {
      running = false;
    } else if (m.type === "onnx" && trainer) {
      const bytes = trainer.onnx();
      post({ type: "onnx", bytes }, [bytes.buffer]);
    }
  } catch (err) {
    post({ type: "error", message: String(err) });
  }
};
