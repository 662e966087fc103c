//! A PNG preview of the summed surface seen from above: height and shaded normal side by side.

use std::path::Path;

use rayon::prelude::*;

use super::{OceanError, Surface};
use crate::image_io::write_png_rgb8;

/// Writes a `2 size_px` x `size_px` RGB PNG of the `extent_m` square centred on the camera
/// origin: height (grey, +-3 RMS) on the left, the normal under a low sun on the right (folded
/// points white). Written atomically.
pub fn write_preview_png(
    surface: &Surface,
    path: &Path,
    size_px: u32,
    extent_m: f64,
) -> Result<(), OceanError> {
    if size_px == 0 || size_px > 16384 {
        return Err(OceanError::invalid(
            "preview size_px",
            "in [1, 16384]",
            size_px,
        ));
    }
    if !extent_m.is_finite() || extent_m <= 0.0 {
        return Err(OceanError::invalid(
            "preview extent_m",
            "finite and > 0",
            extent_m,
        ));
    }
    let sampler = surface.sampler([0.0, 0.0]);
    let s = size_px as usize;
    let w = 2 * s;
    let rms = surface.summary().realization_rms_m.max(1e-6) as f32;
    let sun = {
        let l = [0.5f32, 0.35, 0.3];
        let n = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        [l[0] / n, l[1] / n, l[2] / n]
    };
    let mut rgb = vec![0u8; w * s * 3];
    rgb.par_chunks_mut(w * 3)
        .enumerate()
        .for_each(|(row, out)| {
            let v = ((row as f64 + 0.5) / s as f64 - 0.5) * extent_m;
            for col in 0..s {
                let u = ((col as f64 + 0.5) / s as f64 - 0.5) * extent_m;
                let p = sampler.sample(u as f32, v as f32);
                let g = (((p.height / (3.0 * rms)) * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0) as u8;
                out[3 * col..3 * col + 3].copy_from_slice(&[g, g, g]);
                let n = p.normal;
                let lam = (n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2]).max(0.0);
                let c = |base: f32| ((base * (0.25 + 0.75 * lam)).clamp(0.0, 1.0) * 255.0) as u8;
                let folded = p.jacobian <= 0.0;
                let px = if folded {
                    [255, 255, 255]
                } else {
                    [c(0.35), c(0.65), c(0.95)]
                };
                out[3 * (s + col)..3 * (s + col) + 3].copy_from_slice(&px);
            }
        });
    Ok(write_png_rgb8(path, w as u32, size_px, &rgb)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ocean::{LayerSpec, OceanParams};

    #[test]
    fn preview_png_is_written_atomically() {
        let dir = std::env::temp_dir().join(format!("vastocean-preview-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("ocean.png");
        let p = OceanParams {
            layers: vec![LayerSpec {
                size_m: 100.0,
                n: 64,
            }],
            ..OceanParams::default()
        };
        let s = Surface::new(&p, 7).unwrap();
        write_preview_png(&s, &path, 32, 50.0).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (64, 32));
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "no temporary file left"
        );
        // A folder that cannot be made (its parent is a file): the error names the file.
        let e = write_preview_png(&s, &path.join("dir.png"), 8, 10.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ocean.png/dir.png"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
