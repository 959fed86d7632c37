//! The heads-up display: its CPU image pixel by pixel (text where the font puts it,
//! bars coloured by frame time), and the same image blended onto an offscreen frame by
//! the GPU (needs an adapter: CI installs Mesa's software one, lavapipe).

use flaneur_render::{rasterise, Gpu, GpuMeshes, Hud, HudContent, Offscreen};
use glam::Mat4;
use image::RgbaImage;

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| {
        panic!("{e}\nthe HUD tests need a GPU adapter; .ci/run installs Mesa's software one")
    })
}

fn text(lines: &[&str]) -> HudContent {
    HudContent {
        lines: lines.iter().map(|l| l.to_string()).collect(),
        frame_ms: Vec::new(),
    }
}

#[test]
fn text_is_drawn_where_the_font_says_on_a_translucent_panel() {
    let glyph = font8x8::legacy::BASIC_LEGACY['I' as usize];
    for scale in [1, 2, 3] {
        let image = rasterise(&text(&["I"]), scale);
        let panel = *image.get_pixel(0, 0);
        assert!(panel[3] > 0 && panel[3] < 255, "{panel:?}");
        // The text starts 4·scale pixels in; each font pixel is scale × scale.
        for (row, bits) in glyph.iter().enumerate() {
            for bit in 0..8 {
                let (x, y) = (scale * (4 + bit), scale * (4 + row as u32));
                let p = image.get_pixel(x + scale - 1, y + scale - 1);
                if bits & (1 << bit) != 0 {
                    assert!(p[3] == 255 && p[0] > 200, "{scale}: {x},{y} {p:?}");
                } else {
                    assert_eq!(*p, panel, "{scale}: {x},{y}");
                }
            }
        }
        // Just outside the glyph's cell, and the image's corners: the bare panel.
        let (w, h) = image.dimensions();
        for (x, y) in [
            (scale * 12, scale * 4),
            (w - 1, 0),
            (0, h - 1),
            (w - 1, h - 1),
        ] {
            assert_eq!(*image.get_pixel(x, y), panel, "{scale}: {x},{y}");
        }
    }
    assert_eq!(rasterise(&text(&["I"]), 0), rasterise(&text(&["I"]), 1));
}

#[test]
fn the_image_grows_with_the_text() {
    let (short, long) = ("a".repeat(20), "a".repeat(40));
    let one = rasterise(&text(&[&short]), 1);
    let wider = rasterise(&text(&[&long]), 1);
    let taller = rasterise(&text(&[&short, &short, &short]), 1);
    assert!(wider.width() > one.width(), "{one:?} {wider:?}");
    assert!(taller.height() > one.height() && taller.width() == one.width());
    // No text still leaves room for the graph, at least 120·scale wide.
    let empty = rasterise(&HudContent::default(), 2);
    assert!(empty.width() >= 240 && empty.height() >= 128, "{empty:?}");
    // Too much of everything is cut, not allocated.
    let huge = HudContent {
        lines: vec!["x".repeat(100_000); 10_000],
        frame_ms: vec![f32::NAN, f32::INFINITY, -1.0, 1e30],
    };
    let capped = rasterise(&huge, u32::MAX);
    assert!(capped.width() <= 8 * (8 + 8 * 160) && capped.height() <= 8 * (8 + 480 + 64));
}

#[test]
fn non_ascii_is_drawn_as_a_question_mark() {
    assert_eq!(rasterise(&text(&["é→x"]), 2), rasterise(&text(&["??x"]), 2));
    assert_ne!(rasterise(&text(&["x"]), 1), rasterise(&text(&["?"]), 1));
}

/// The columns of `image` holding pixels of `colour`, with how many each holds.
fn columns_of(image: &RgbaImage, colour: fn(&[u8; 4]) -> bool) -> Vec<(u32, usize)> {
    (0..image.width())
        .map(|x| {
            let n = (0..image.height())
                .filter(|&y| colour(&image.get_pixel(x, y).0))
                .count();
            (x, n)
        })
        .filter(|&(_, n)| n > 0)
        .collect()
}

#[test]
fn bars_are_as_tall_as_the_frame_time_and_coloured_by_it() {
    let content = HudContent {
        lines: vec!["frame times".into()],
        frame_ms: vec![10.0, 40.0, 60.0],
    };
    let image = rasterise(&content, 1);
    let green = columns_of(&image, |p| p[1] > 150 && p[0] < 120 && p[3] == 255);
    let yellow = columns_of(&image, |p| p[0] > 200 && p[1] > 150 && p[2] < 100);
    let red = columns_of(&image, |p| p[0] > 200 && p[1] < 100 && p[3] == 255);
    // One pixel a millisecond, newest on the right; the 50 ms line crosses the red bar.
    assert_eq!(green.len(), 1, "{green:?}");
    assert_eq!(yellow.len(), 1, "{yellow:?}");
    assert_eq!(red.len(), 1, "{red:?}");
    assert_eq!(green[0].1, 10);
    assert_eq!(yellow[0].1, 40);
    assert!((59..=60).contains(&red[0].1), "{red:?}");
    assert_eq!((yellow[0].0, red[0].0), (green[0].0 + 1, green[0].0 + 2));
    assert_eq!(red[0].0, image.width() - 5, "the newest bar ends the graph");
}

/// sRGB byte to linear light, and back.
fn linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
fn srgb(l: f32) -> u8 {
    let c = if l <= 0.0031308 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// `over` (straight alpha) on the opaque `under`, blended in linear light as an sRGB
/// target does.
fn composite(over: [u8; 4], under: &[u8]) -> [u8; 3] {
    let a = over[3] as f32 / 255.0;
    std::array::from_fn(|i| srgb(a * linear(over[i]) + (1.0 - a) * linear(under[i])))
}

#[test]
fn the_gpu_blends_the_image_onto_a_frame_and_keeps_its_texture() {
    let gpu = gpu();
    let (w, h) = (200, 120);
    let offscreen = Offscreen::new(&gpu, w, h).unwrap();
    let meshes = GpuMeshes::default();
    let plain = offscreen
        .render(&gpu, Mat4::IDENTITY, &meshes, &[])
        .unwrap();
    let content = HudContent {
        lines: vec!["FPS 60.0".into(), "objects 1234".into()],
        frame_ms: vec![10.0, 20.0, 40.0, 45.0, 60.0, 80.0],
    };
    let mut hud = Hud::new(&gpu, offscreen.colour_format()).unwrap();
    assert_eq!(hud.texture_size(), (0, 0));
    let draw = |hud: &mut Hud, content: &HudContent| {
        offscreen
            .render_then(&gpu, Mat4::IDENTITY, &meshes, &[], |enc, view| {
                hud.draw(&gpu, enc, view, (w, h), content, 1)
            })
            .unwrap()
    };
    let frame = draw(&mut hud, &content);
    let image = rasterise(&content, 1);
    let size = hud.texture_size();
    assert_eq!(size, image.dimensions());

    let at = |rgba: &[u8], x: u32, y: u32| {
        let i = 4 * (y * w + x) as usize;
        rgba[i..i + 4].to_vec()
    };
    let (iw, ih) = image.dimensions();
    let mut text_pixels = 0;
    for y in 0..h {
        for x in 0..w {
            let (got, sky) = (at(&frame.rgba, x, y), at(&plain.rgba, x, y));
            let inside = (8..8 + iw).contains(&x) && (8..8 + ih).contains(&y);
            if !inside {
                assert_eq!(got, sky, "{x},{y} is away from the HUD");
                continue;
            }
            let over = image.get_pixel(x - 8, y - 8).0;
            let want = composite(over, &sky);
            let near = (0..3).all(|i| got[i].abs_diff(want[i]) <= 3);
            assert!(
                near,
                "{x},{y}: {got:?}, want {want:?} ({over:?} over {sky:?})"
            );
            assert_ne!(got, sky, "{x},{y}: the panel darkens the sky");
            if over[3] == 255 && over[0] > 200 && over[1] > 200 {
                text_pixels += 1;
            }
        }
    }
    assert!(text_pixels > 50, "{text_pixels} text pixels");

    // The same content again: the same texture and the same pixels.
    assert_eq!(draw(&mut hud, &content), frame);
    assert_eq!(hud.texture_size(), size);
    // Less content fits the texture there is; more grows it.
    draw(&mut hud, &text(&["a"]));
    assert_eq!(hud.texture_size(), size);
    draw(&mut hud, &text(&["a", "b", "c", "d"]));
    assert!(hud.texture_size().1 > size.1 && hud.texture_size().0 == size.0);
}

#[test]
fn the_hud_is_clipped_to_a_small_target() {
    let gpu = gpu();
    let offscreen = Offscreen::new(&gpu, 40, 30).unwrap();
    let mut hud = Hud::new(&gpu, offscreen.colour_format()).unwrap();
    let content = text(&["a long line that cannot fit"]);
    let frame = offscreen
        .render_then(
            &gpu,
            Mat4::IDENTITY,
            &GpuMeshes::default(),
            &[],
            |enc, view| hud.draw(&gpu, enc, view, (40, 30), &content, 2),
        )
        .unwrap();
    assert_eq!(hud.texture_size(), (32, 22));
    // The far corner shows the image's pixel (31, 21), the rest of it cut off.
    let over = rasterise(&content, 2).get_pixel(31, 21).0;
    let corner = &frame.rgba[4 * (29 * 40 + 39)..][..4];
    let want = composite(over, &frame.rgba[..4]);
    assert!(
        (0..3).all(|i| corner[i].abs_diff(want[i]) <= 3),
        "{corner:?}, want {want:?}"
    );
}

#[test]
fn a_target_of_zero_size_is_an_error() {
    let gpu = gpu();
    let offscreen = Offscreen::new(&gpu, 16, 16).unwrap();
    let mut hud = Hud::new(&gpu, offscreen.colour_format()).unwrap();
    let result = offscreen.render_then(
        &gpu,
        Mat4::IDENTITY,
        &GpuMeshes::default(),
        &[],
        |enc, view| hud.draw(&gpu, enc, view, (0, 10), &HudContent::default(), 1),
    );
    match result {
        Err(flaneur::Error::Invalid(msg)) => assert!(msg.contains("0 × 10"), "{msg}"),
        other => panic!("expected an error, got {:?}", other.map(|f| f.width)),
    }
    // A target too small to show anything is no error: nothing is drawn.
    let frame = offscreen
        .render_then(
            &gpu,
            Mat4::IDENTITY,
            &GpuMeshes::default(),
            &[],
            |enc, view| hud.draw(&gpu, enc, view, (8, 8), &HudContent::default(), 1),
        )
        .unwrap();
    assert!(frame.rgba.chunks(4).all(|p| p == &frame.rgba[..4]));
}
