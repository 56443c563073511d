// Run the COCO-trained MobileNetV3-CenterNet (install.sh puts its files in model/) on images
// that seahaze.metric.centernet has already resized to the model's 512×512 input.
//
// Usage: node detect.mjs JOB.json
// JOB.json: {"inputs": ["a.rgb", ...], "size": 512, "out": "detections.json"}; each input holds
// size×size×3 bytes (RGB, row-major). Writes, per input, the model's own decoded detections
// [x0, y0, x1, y1, score, coco_index] in input pixels. Nothing is fetched: the model files are
// read from model/, and the WebAssembly binaries from their npm package.
import * as tf from '@tensorflow/tfjs-core';
import * as converter from '@tensorflow/tfjs-converter';
import { setWasmPaths } from '@tensorflow/tfjs-backend-wasm';
import { readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const require = createRequire(import.meta.url);
const wasmDir = path.dirname(require.resolve('@tensorflow/tfjs-backend-wasm/dist/tfjs-backend-wasm.wasm'));
const modelDir = path.join(path.dirname(fileURLToPath(import.meta.url)), 'model');

async function loadModel() {
  const spec = JSON.parse(readFileSync(path.join(modelDir, 'centernet.json'), 'utf8'));
  // One weights file: the manifest's single group names it.
  const [group] = spec.weightsManifest;
  const bytes = readFileSync(path.join(modelDir, group.paths[0]));
  const weightData = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  return converter.loadGraphModel(tf.io.fromMemory({
    modelTopology: spec.modelTopology, weightSpecs: group.weights, weightData,
  }));
}

const job = JSON.parse(readFileSync(process.argv[2], 'utf8'));
setWasmPaths(wasmDir + path.sep);
await tf.setBackend('wasm');
await tf.ready();
const model = await loadModel();
const results = [];
for (const input of job.inputs) {
  const bytes = readFileSync(input);
  if (bytes.length !== job.size * job.size * 3) throw new Error(`${input}: not ${job.size}x${job.size} RGB`);
  // The model takes pixel values 0–255 as floats, NHWC (as @vladmandic/human feeds it).
  const image = tf.tensor(Float32Array.from(bytes), [1, job.size, job.size, 3]);
  const out = model.execute(image, ['tower_0/detections']);
  const [rows] = await out.array();
  tf.dispose([image, out]);
  results.push(rows);
}
writeFileSync(job.out, JSON.stringify({ backend: tf.getBackend(), tfjs: tf.version_core, detections: results }));
