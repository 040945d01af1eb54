//! Policy files into the loader (`chopperscape-policy`): arbitrary bytes, or the committed policy with
//! arbitrary bytes overwritten (so that the fuzzer reaches the graph and metadata checks, not only the protobuf
//! decoder). Loading must return an error or a policy that acts on a zero observation; a panic inside tract is
//! caught by the loader and is an error too, so the panic hook is silenced (a panic that escapes still aborts).
#![no_main]
use chopperscape::Observation;
use chopperscape_policy::Policy;
use libfuzzer_sys::fuzz_target;

const MODEL: &[u8] = include_bytes!("../../models/ppo-features.onnx");

/// The model with `edits` applied: each 3 bytes are an offset (u16, little-endian, scaled over the file) and
/// the byte written there.
fn edited(edits: &[u8]) -> Vec<u8> {
    let mut bytes = MODEL.to_vec();
    for e in edits.chunks_exact(3) {
        let at = usize::from(u16::from_le_bytes([e[0], e[1]])) * bytes.len() / 65536;
        bytes[at] = e[2];
    }
    bytes
}

fuzz_target!(|data: &[u8]| {
    static QUIET: std::sync::Once = std::sync::Once::new();
    QUIET.call_once(|| std::panic::set_hook(Box::new(|_| {})));
    let bytes = match data.split_first() {
        Some((mode, edits)) if mode & 1 == 1 => edited(edits),
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
