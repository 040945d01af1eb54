//! Policy files into the loader (`chopperscape-policy`): arbitrary bytes, or one of the committed exports (the
//! features MLP or the pixel CNN, `models/*.onnx`) with arbitrary bytes overwritten, so that the fuzzer reaches
//! the graph, limit and metadata checks, not only the protobuf decoder. Seeds: `fuzz/seeds/policy_load/` (both
//! exports unedited, and the hostile graphs of issue 32). Loading must return an error, or a policy that acts on a
//! zero observation, within the loader's limits (`docs/limits.md`); a panic inside tract is caught by the loader
//! and is an error too, and prints nothing (the loader silences the hook on its thread). A panic that escapes
//! reaches libFuzzer's hook and aborts: a finding.
#![no_main]
use chopperscape::Observation;
use chopperscape_policy::Policy;
use libfuzzer_sys::fuzz_target;

const FEATURES: &[u8] = include_bytes!("../../models/ppo-features.onnx");
const PIXELS: &[u8] = include_bytes!("../../models/ppo-pixels.onnx");

/// `model` with `edits` applied: each 3 bytes are an offset (u16, little-endian, scaled over the file) and the
/// byte written there.
fn edited(model: &[u8], edits: &[u8]) -> Vec<u8> {
    let mut bytes = model.to_vec();
    for e in edits.chunks_exact(3) {
        let at = usize::from(u16::from_le_bytes([e[0], e[1]])) * bytes.len() / 65536;
        bytes[at] = e[2];
    }
    bytes
}

fuzz_target!(|data: &[u8]| {
    // The first byte chooses: bit 0 clear, the bytes as they are; set, an export edited by the rest, the pixel
    // CNN when bit 1 is set too (its graph and metadata lie in its first and last few KB; the offsets scale
    // over the whole file, so most edits land in its weights).
    let bytes = match data.split_first() {
        Some((mode, edits)) if mode & 1 == 1 => edited(if mode & 2 == 2 { PIXELS } else { FEATURES }, edits),
        _ => data.to_vec(),
    };
    if let Ok(mut policy) = Policy::from_bytes(&bytes) {
        let meta = policy.metadata();
        let dtype = if meta.obs_type.is_pixels() && meta.obs_type != chopperscape::ObsType::RgbFloat {
            chopperscape::Dtype::U8
        } else {
            chopperscape::Dtype::F32
        };
        let obs = Observation::zeros(meta.obs_shape.clone(), dtype);
        let _ = policy.act(&obs);
    }
});
