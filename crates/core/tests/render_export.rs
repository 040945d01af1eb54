//! Image export: PNG frames decode to the exact pixels, GIF and APNG episodes hold every frame, bad input is
//! refused with a clear error, and saving to a path never leaves a half-written file.

#![cfg(feature = "export")]

use chopperscape::export::{self, ApngWriter, ExportError, GifWriter};
use chopperscape::render::PixelFormat;
use chopperscape::{ChopperScape, Config, Env};

/// The first `n` full frames of a seeded episode.
fn episode(n: usize) -> Vec<Vec<u8>> {
    let mut env = ChopperScape::new(Config { bird_prob: 0.3, ..Config::features() }).unwrap();
    env.reset(Some(4));
    (0..n)
        .map(|t| {
            env.step((t % 5) as i64).unwrap();
            env.render()
        })
        .collect()
}

#[test]
fn png_round_trips_rgb_and_gray_frames_exactly() {
    let frame = episode(3).pop().unwrap();
    let mut bytes = Vec::new();
    export::write_png(&mut bytes, &frame, 600, 800, PixelFormat::Rgb).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
    let mut back = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut back).unwrap();
    assert_eq!((info.width, info.height, info.color_type), (800, 600, png::ColorType::Rgb));
    assert!(back == frame);

    let gray: Vec<u8> = (0..=255).collect();
    let mut bytes = Vec::new();
    export::write_png(&mut bytes, &gray, 16, 16, PixelFormat::Gray).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
    let mut back = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut back).unwrap();
    assert_eq!(back, gray);
}

#[test]
fn a_frame_of_the_wrong_size_is_refused() {
    let err = export::write_png(Vec::new(), &[0; 10], 2, 2, PixelFormat::Rgb).unwrap_err();
    assert!(matches!(err, ExportError::FrameSize { expected: 12, got: 10, .. }));
    assert!(err.to_string().contains("a 2x2 Rgb frame has 12"), "{err}");
}

#[test]
fn gif_holds_every_frame_with_exact_colours() {
    let frames = episode(4);
    let mut gif = GifWriter::new(Vec::new(), 600, 800, PixelFormat::Rgb, 30).unwrap();
    for f in &frames {
        gif.push(f).unwrap();
    }
    let bytes = gif.finish().unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::io::Cursor::new(bytes)).unwrap();
    let mut n = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!(frame.delay, 3, "30 fps is 3 hundredths a frame");
        let rgb: Vec<u8> = frame.buffer.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        assert!(rgb == frames[n], "frame {n} differs");
        n += 1;
    }
    assert_eq!(n, frames.len());
}

#[test]
fn gif_of_many_colours_is_quantized_rather_than_refused() {
    let frame: Vec<u8> = (0..64 * 64).flat_map(|i: u32| [(i % 64 * 4) as u8, (i / 64 * 4) as u8, 128]).collect();
    let mut gif = GifWriter::new(Vec::new(), 64, 64, PixelFormat::Rgb, 30).unwrap();
    gif.push(&frame).unwrap();
    assert!(gif.finish().unwrap().starts_with(b"GIF89a"));
}

#[test]
fn apng_announces_and_holds_every_frame() {
    let frames = episode(3);
    let mut out = Vec::new();
    {
        let mut apng = ApngWriter::new(&mut out, 600, 800, PixelFormat::Rgb, 30, frames.len()).unwrap();
        for f in &frames {
            apng.push(f).unwrap();
        }
        apng.finish().unwrap();
    }
    let mut reader = png::Decoder::new(std::io::Cursor::new(out)).read_info().unwrap();
    let control = reader.info().animation_control.expect("an animated PNG");
    assert_eq!((control.num_frames, control.num_plays), (3, 0));
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    for (i, f) in frames.iter().enumerate() {
        reader.next_frame(&mut buf).unwrap();
        assert!(buf == *f, "frame {i} differs");
    }
}

#[test]
fn apng_with_fewer_or_more_frames_than_announced_is_an_error() {
    let f = vec![255u8; 4 * 4 * 3];
    let mut apng = ApngWriter::new(Vec::new(), 4, 4, PixelFormat::Rgb, 30, 2).unwrap();
    apng.push(&f).unwrap();
    assert!(matches!(apng.finish(), Err(ExportError::FrameCount { announced: 2, got: 1 })));
    let mut apng = ApngWriter::new(Vec::new(), 4, 4, PixelFormat::Rgb, 30, 1).unwrap();
    apng.push(&f).unwrap();
    assert!(matches!(apng.push(&f), Err(ExportError::FrameCount { announced: 1, got: 2 })));
    assert!(matches!(ApngWriter::new(Vec::new(), 4, 4, PixelFormat::Rgb, 0, 1), Err(ExportError::Fps(0))));
}

#[test]
fn saving_atomically_keeps_the_old_file_when_writing_fails() {
    let dir = std::env::temp_dir().join(format!("chopperscape-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("frame.png");
    std::fs::write(&path, b"old").unwrap();
    let err = export::save_atomically(&path, |w| export::write_png(w, &[0; 5], 2, 2, PixelFormat::Rgb));
    assert!(err.is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary file left behind");
    export::save_atomically(&path, |w| export::write_png(w, &[9; 12], 2, 2, PixelFormat::Rgb)).unwrap();
    assert!(std::fs::read(&path).unwrap().starts_with(b"\x89PNG"));
    std::fs::remove_dir_all(&dir).unwrap();
}
