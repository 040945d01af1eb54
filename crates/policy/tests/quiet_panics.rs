//! A panic inside tract is an error, and prints nothing: the loader silences the panic hook on its own thread
//! while tract runs, and forwards every other panic to the hook that was there. (One test alone in its binary:
//! it sets the process's panic hook.)

use std::sync::atomic::{AtomicUsize, Ordering};

use chopperscape_policy::{Policy, PolicyError};
use prost::Message;
use tract_onnx::pb::{AttributeProto, ModelProto, NodeProto, TensorProto};

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");

static PRINTED: AtomicUsize = AtomicUsize::new(0);

/// The committed policy with a `Gather` of index 1000 from a constant of 2 elements added to the observation:
/// tract indexes out of bounds while it computes the constant (`gather.rs`), in release builds too.
fn panicking_model() -> Vec<u8> {
    let mut m = ModelProto::decode(&*std::fs::read(FEATURES).unwrap()).unwrap();
    let g = m.graph.as_mut().unwrap();
    let node = |op: &str, inputs: &[&str], output: &str, attribute: Vec<AttributeProto>| NodeProto {
        op_type: op.into(),
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.into()],
        attribute,
        ..Default::default()
    };
    g.node = vec![
        node("Gather", &["c", "i"], "g", vec![AttributeProto { name: "axis".into(), r#type: 2, ..Default::default() }]),
        node("Add", &["obs", "g"], "logits", vec![]),
    ];
    g.initializer = vec![
        TensorProto { name: "c".into(), dims: vec![2], data_type: 1, float_data: vec![1.0, 2.0], ..Default::default() },
        TensorProto { name: "i".into(), dims: vec![1], data_type: 7, int64_data: vec![1000], ..Default::default() },
    ];
    m.encode_to_vec()
}

#[test]
fn a_panic_inside_tract_is_an_error_that_prints_nothing() {
    std::panic::set_hook(Box::new(|_| {
        PRINTED.fetch_add(1, Ordering::SeqCst);
    }));
    let err = Policy::from_bytes(&panicking_model()).unwrap_err();
    assert!(matches!(err, PolicyError::Run(_)), "{err:?}");
    let text = err.to_string();
    assert!(text.contains("the inference engine failed (index out of bounds"), "{text}");
    assert_eq!(PRINTED.load(Ordering::SeqCst), 0, "the hook saw tract's panic");
    // Twice, from another thread too: the hook is installed once, and silent only where tract runs.
    std::thread::spawn(|| assert!(Policy::from_bytes(&panicking_model()).is_err())).join().unwrap();
    assert_eq!(PRINTED.load(Ordering::SeqCst), 0);
    let outside = std::panic::catch_unwind(|| panic!("a panic of the program's own"));
    assert!(outside.is_err());
    assert_eq!(PRINTED.load(Ordering::SeqCst), 1, "the program's own panics still reach its hook");
    // The committed policy still loads with the hook in place.
    Policy::load(FEATURES).unwrap();
}
