//! The image readers on mutated files: EXR, HDR, PNG and JPEG seeds, byte-level mutations,
//! no panic (see `lightlab_core::fuzz`).

use glam::Vec3;
use lightlab_core::fuzz::Fuzzer;
use lightlab_core::image::{Image, LdrSettings};
use std::path::Path;

fn seeds() -> Vec<(&'static str, Vec<u8>, bool)> {
    let img = Image::from_fn(19, 7, |x, y| Vec3::new(x as f32 * 0.3, y as f32 * 0.7, 1.5));
    let exr = img
        .encode(Path::new("a.exr"), LdrSettings::default())
        .unwrap();
    let png = img
        .encode(Path::new("a.png"), LdrSettings::default())
        .unwrap();
    let rgb: Vec<image::Rgb<f32>> = img.data.iter().map(|v| image::Rgb(v.to_array())).collect();
    let mut hdr = vec![];
    image::codecs::hdr::HdrEncoder::new(&mut hdr)
        .encode(&rgb, 19, 7)
        .unwrap();
    let mut jpg = std::io::Cursor::new(vec![]);
    image::DynamicImage::ImageRgb8(
        image::RgbImage::from_raw(19, 7, img.to_srgb8(LdrSettings::default())).unwrap(),
    )
    .write_to(&mut jpg, image::ImageFormat::Jpeg)
    .unwrap();
    vec![
        ("exr", exr, true),
        ("hdr", hdr, true),
        ("png", png, false),
        ("jpg", jpg.into_inner(), false),
    ]
}

#[test]
fn mutated_images_never_panic() {
    let seeds = seeds();
    for (ext, bytes, linear) in &seeds {
        let p = Path::new("seed").with_extension(ext);
        let back = Image::decode(&p, bytes, *linear).unwrap();
        assert_eq!((back.width, back.height), (19, 7), "{ext}");
    }
    let mut fuzz = Fuzzer::from_env(2500, 0x696d_6167_6573);
    for round in 0..fuzz.rounds {
        for (ext, bytes, linear) in &seeds {
            let input = fuzz.mutated_bytes(bytes);
            let p = Path::new("fuzzed").with_extension(ext);
            fuzz.run(&format!("round {round}, {ext}"), &input, || {
                Image::decode(&p, &input, *linear).is_ok()
            });
        }
    }
    let min = 4 * fuzz.rounds as usize;
    fuzz.finish("image", min);
}
