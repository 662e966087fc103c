//! Image files: linear-RGB OpenEXR (exr crate) read and write, tone-mapped sRGB PNG previews,
//! and JSON sidecars. Every writer goes through [`write_atomically`]: the file appears under its
//! final name complete or not at all (DESIGN.md, Errors: never a partial output file).

use std::io::Write;
use std::path::{Path, PathBuf};

use thiserror::Error;

pub use crate::config::ExrCompression;

mod atomic;
pub use atomic::{
    Staged, TEMP_MARKER, WriteError, commit_all, remove_temps, stage, sweep_stale_temps,
    write_atomically,
};

#[derive(Debug, Error)]
pub enum ImageError {
    #[error(transparent)]
    Write(#[from] WriteError),
    #[error("cannot read {}: {message}", path.display())]
    Read { path: PathBuf, message: String },
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
}

/// A linear-RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    pub fn new(width: usize, height: usize) -> RgbImage {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
        }
    }
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
}

/// Writes a linear-RGB EXR (32-bit float channels R, G, B, uncompressed).
pub fn write_exr(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    write_exr_with(path, img, &[], ExrCompression::None)
}

/// Writes a linear-RGB EXR (32-bit float) with further f32 channels, e.g. `Y.variance`.
pub fn write_exr_with(
    path: &Path,
    img: &RgbImage,
    extra: &[(&str, &[f32])],
    compression: ExrCompression,
) -> Result<(), ImageError> {
    Ok(stage_exr_with(path, img, extra, compression)?.commit()?)
}

/// [`write_exr_with`], staged (see [`commit_all`]). PIZ and ZIP compress blocks in parallel
/// (the exr crate's writer, on a pool of its own); uncompressed blocks are written as they are.
pub fn stage_exr_with(
    path: &Path,
    img: &RgbImage,
    extra: &[(&str, &[f32])],
    compression: ExrCompression,
) -> Result<Staged, ImageError> {
    use exr::prelude::*;
    let n = img.width * img.height;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let samples = img.pixels.iter().map(|p| p[k]).collect();
            AnyChannel::new(*name, FlatSamples::F32(samples))
        })
        .collect();
    for (name, values) in extra {
        assert_eq!(values.len(), n, "one value per pixel for channel {name}");
        list.push(AnyChannel::new(*name, FlatSamples::F32(values.to_vec())));
    }
    let mut layer = Layer::new(
        (img.width, img.height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    layer.encoding.compression = match compression {
        ExrCompression::None => Compression::Uncompressed,
        ExrCompression::Piz => Compression::PIZ,
        ExrCompression::Zip => Compression::ZIP16,
    };
    let image = Image::from_layer(layer);
    Ok(stage(path, |w| {
        image
            .write()
            .to_buffered(w)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })?)
}

/// Reads one f32 channel of the first layer of an EXR file, row-major.
pub fn read_exr_channel(path: &Path, name: &str) -> Result<Vec<f32>, ImageError> {
    use exr::prelude::*;
    let image = read_all_flat_layers_from_file(path).map_err(|e| ImageError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let channel = image
        .layer_data
        .first()
        .and_then(|l| {
            l.channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == name)
        })
        .ok_or_else(|| ImageError::Invalid {
            path: path.to_path_buf(),
            message: format!("no channel {name}"),
        })?;
    Ok(channel.sample_data.values_as_f32().collect())
}

/// Reads the RGB channels of the first layer of an EXR file as linear f32.
pub fn read_exr(path: &Path) -> Result<RgbImage, ImageError> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| RgbImage::new(res.width(), res.height()),
        |img: &mut RgbImage, p: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[p.y() * w + p.x()] = [r, g, b];
        },
    )
    .map_err(|e| ImageError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// sRGB transfer function of a linear value in [0, 1].
fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Tone-maps linear RGB to 8-bit sRGB: exposure scaling, then the ACES filmic curve fit of
/// Narkowicz (2015), then the sRGB transfer function.
pub fn tonemap(c: [f32; 3], exposure: f32) -> [u8; 3] {
    c.map(|v| {
        let x = (v * exposure).max(0.0);
        let y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
        (srgb_encode(y.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8
    })
}

/// An exposure that maps the image's median luminance to mid grey (0.18): previews of very
/// different skies all come out readable.
pub fn auto_exposure(img: &RgbImage) -> f32 {
    use rayon::prelude::*;
    let mut lum: Vec<f32> = img
        .pixels
        .par_iter()
        .map(|&c| crate::color::luminance(c))
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    let mid = lum.len() / 2;
    let (_, median, _) = lum.select_nth_unstable_by(mid, f32::total_cmp);
    0.18 / *median
}

/// The exposure factor a PNG preview of `img` uses for `render.exposure` (stops, or `None` for
/// [`auto_exposure`]), and the same in stops (what a report shows, and what a user can pass
/// back as `--exposure` to keep it).
pub fn png_exposure(stops: Option<f32>, img: &RgbImage) -> (f32, f32) {
    match stops {
        Some(stops) => (stops.exp2(), stops),
        None => {
            let factor = auto_exposure(img);
            (factor, factor.log2())
        }
    }
}

/// Writes an 8-bit sRGB PNG preview of a linear image.
pub fn write_png(path: &Path, img: &RgbImage, exposure: f32) -> Result<(), ImageError> {
    Ok(stage_png(path, img, exposure)?.commit()?)
}

/// [`write_png`], staged (see [`commit_all`]).
pub fn stage_png(path: &Path, img: &RgbImage, exposure: f32) -> Result<Staged, ImageError> {
    use rayon::prelude::*;
    let mut bytes = vec![0u8; img.pixels.len() * 3];
    // rows side by side (on the calling pool): the tone curve's powers were a tenth of a second
    // of the default render on one core
    let row = img.width.max(1);
    bytes
        .par_chunks_mut(3 * row)
        .zip(img.pixels.par_chunks(row))
        .for_each(|(out, pixels)| {
            for (o, &c) in out.chunks_exact_mut(3).zip(pixels) {
                o.copy_from_slice(&tonemap(c, exposure));
            }
        });
    stage_png_rgb8(path, img.width as u32, img.height as u32, &bytes)
}

/// Writes raw 8-bit RGB rows as a PNG.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ImageError> {
    Ok(stage_png_rgb8(path, width, height, rgb)?.commit()?)
}

fn stage_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<Staged, ImageError> {
    Ok(stage(path, |w| {
        let mut enc = png::Encoder::new(w, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        // The PNG is a preview: fdeflate's fast mode encodes the default 2048 x 1024 image in a
        // few tens of milliseconds where the default level took about a second on one core
        // (docs/performance.md), for a somewhat larger file.
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(rgb)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })?)
}

/// Writes a value as pretty JSON.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<(), ImageError> {
    Ok(stage_json(path, value)?.commit()?)
}

/// [`write_json`], staged (see [`commit_all`]).
pub fn stage_json(path: &Path, value: &impl serde::Serialize) -> Result<Staged, ImageError> {
    Ok(stage(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?)
}

/// Writes a linear-RGB EXR with half-float (f16) channels R, G, B and ZIP compression, the
/// compact form for shipped sky maps (on them 0.65 of PIZ's bytes in all, read in half its
/// time: docs/performance.md, "Output"). Values beyond half's range (65504) are refused
/// rather than written as infinity.
pub fn write_exr_half(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    use exr::prelude::*;
    let max = f16::MAX.to_f32();
    if let Some(i) = img
        .pixels
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite() || c.abs() > max))
    {
        return Err(ImageError::Invalid {
            path: path.to_path_buf(),
            message: format!(
                "texel ({}, {}) is {:?}: not representable as half float (finite, |x| <= 65504)",
                i % img.width.max(1),
                i / img.width.max(1),
                img.pixels[i]
            ),
        });
    }
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = img.get(p.x(), p.y());
        (
            f16::from_f32(c[0]),
            f16::from_f32(c[1]),
            f16::from_f32(c[2]),
        )
    });
    let mut layer = Layer::new(
        (img.width, img.height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    layer.encoding.compression = Compression::ZIP16;
    let image = Image::from_layer(layer);
    Ok(write_atomically(path, |w| {
        image
            .write()
            .to_buffered(w)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn exr_round_trip_is_lossless_for_f32() {
        let dir = std::env::temp_dir().join(format!("vastocean-exr-{}", std::process::id()));
        let path = dir.join("t.exr");
        let mut img = RgbImage::new(7, 3);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 0.1, 1e-7 * i as f32, 12345.678 + i as f32];
        }
        write_exr(&path, &img).unwrap();
        assert_eq!(read_exr(&path).unwrap(), img);
        // Each compression on a render-like image: noisy floats of every magnitude, an extra
        // channel, sizes that are not multiples of the blocks; every bit comes back, and the
        // file says which compression it holds.
        let (w, h) = (67, 45);
        let mut img = RgbImage::new(w, h);
        let mut rng = crate::rng::Rng::keyed(&[7]);
        let mut bits = || f32::from_bits(rng.next_u64() as u32 & 0x7f7f_ffff);
        for p in img.pixels.iter_mut() {
            *p = [bits(), bits() * 1e-30, bits()];
        }
        img.pixels[0] = [0.0, -0.0, f32::MIN_POSITIVE / 3.0];
        let var: Vec<f32> = (0..w * h).map(|_| bits()).collect();
        for (c, stored) in [
            (
                ExrCompression::None,
                exr::compression::Compression::Uncompressed,
            ),
            (ExrCompression::Piz, exr::compression::Compression::PIZ),
            (ExrCompression::Zip, exr::compression::Compression::ZIP16),
        ] {
            write_exr_with(&path, &img, &[("Y.variance", &var)], c).unwrap();
            let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
            assert_eq!(meta.headers[0].compression, stored, "{c}");
            let back = read_exr(&path).unwrap();
            assert!(
                back.pixels
                    .iter()
                    .flatten()
                    .zip(img.pixels.iter().flatten())
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{c}"
            );
            let var_back = read_exr_channel(&path, "Y.variance").unwrap();
            assert!(
                var_back
                    .iter()
                    .zip(&var)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{c}"
            );
        }
        let _ = fs::remove_dir_all(dir);
    }

    #[test]
    fn the_preview_holds_each_pixel_tone_mapped_in_place() {
        // rows are tone-mapped side by side: every byte as the pixel's own tonemap gives it
        let dir = std::env::temp_dir().join(format!("vastocean-png-{}", std::process::id()));
        let path = dir.join("p.png");
        let (w, h) = (37, 23);
        let mut img = RgbImage::new(w, h);
        let mut rng = crate::rng::Rng::keyed(&[11]);
        for p in img.pixels.iter_mut() {
            *p = std::array::from_fn(|_| (rng.f64() * 3.0) as f32);
        }
        write_png(&path, &img, 0.7).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width as usize, info.height as usize), (w, h));
        let want: Vec<u8> = img.pixels.iter().flat_map(|&c| tonemap(c, 0.7)).collect();
        assert_eq!(&buf[..info.buffer_size()], &want[..]);
        let _ = fs::remove_dir_all(dir);
    }

    #[test]
    fn tonemap_is_monotonic_and_bounded() {
        let a = tonemap([0.0, 0.1, 100.0], 1.0);
        assert_eq!(a[0], 0);
        assert!(a[1] > 0 && a[2] == 255);
        assert!(tonemap([0.2; 3], 1.0)[0] < tonemap([0.3; 3], 1.0)[0]);
    }
}
