//! `sky generate | import | info | sheet`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;
use vastocean::app;

use super::choice;
use crate::emit;

#[derive(Subcommand)]
pub enum SkyCommand {
    /// Generate a sky map (half-float EXR).
    #[command(allow_negative_numbers = true)]
    Generate {
        #[arg(long, value_parser = choice::<vastocean::sky::procedural::SkyKind>())]
        kind: vastocean::sky::procedural::SkyKind,
        /// Sun elevation above the horizon, degrees (-10..=90; sets the overcast sky's brightness).
        #[arg(long)]
        sun_elevation: f64,
        /// Sun azimuth, degrees (0 = +x, 90 = +z).
        #[arg(long, default_value_t = 180.0)]
        sun_azimuth: f64,
        /// Atmospheric turbidity (Preetham: 2 very clear, 6 hazy).
        #[arg(long, default_value_t = 2.5)]
        turbidity: f64,
        /// Covered fraction of the cloud layer (partly cloudy).
        #[arg(long, default_value_t = 0.4)]
        cloud_cover: f64,
        /// Seed of the clouds (partly cloudy).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Map width, texels (height = width / 2), 16 to 16384.
        #[arg(long, default_value_t = 1024, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(16..=16384))]
        width: usize,
        /// The sky map to write (EXR, half float).
        #[arg(long)]
        out: PathBuf,
    },
    /// Import an equirectangular HDR photograph: remove the ground, optionally rotate the sun.
    #[command(allow_negative_numbers = true)]
    Import {
        /// Equirectangular HDR photograph (EXR, horizon at the middle row).
        photo: PathBuf,
        /// The sky map to write (EXR, half float), the ground below the horizon replaced.
        #[arg(long)]
        out: PathBuf,
        /// What to put below the horizon.
        #[arg(long, value_parser = choice::<vastocean::sky::tools::Ground>(), default_value = "fill")]
        ground: vastocean::sky::tools::Ground,
        /// Rotate the map in azimuth so the brightest region (the sun) lands here, degrees.
        #[arg(long)]
        sun_azimuth: Option<f64>,
        /// Set negative components (left by colour-space conversions) to zero instead of refusing.
        #[arg(long)]
        clamp_negative: bool,
    },
    /// Resolution, mean and peak luminance, sun direction, energy near the horizon.
    Info {
        /// Equirectangular EXR sky map.
        file: PathBuf,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// A tone-mapped PNG contact sheet of sky maps, in the order given.
    Sheet {
        /// Equirectangular EXR sky maps.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Width of each thumbnail, pixels, 16 to 2048.
        #[arg(long, default_value_t = 384, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(16..=2048))]
        thumb_width: usize,
        /// Thumbnails per row, 1 to 16.
        #[arg(long, default_value_t = 3, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=16))]
        columns: usize,
        /// The contact sheet to write (PNG).
        #[arg(long)]
        out: PathBuf,
    },
}

pub fn run(c: SkyCommand) -> Result<()> {
    match c {
        #[rustfmt::skip]
        SkyCommand::Generate { kind, sun_elevation, sun_azimuth, turbidity, cloud_cover, seed, width, out } => {
            let params = vastocean::sky::procedural::SkyParams {
                kind,
                sun_elevation_deg: sun_elevation,
                sun_azimuth_deg: sun_azimuth,
                turbidity,
                cloud_cover,
                seed,
            };
            let (w, h) = app::sky::generate(&params, width, &out)?;
            eprintln!("wrote {} ({w} x {h})", out.display());
        }
        #[rustfmt::skip]
        SkyCommand::Import { photo, out, ground, sun_azimuth, clamp_negative } => {
            let job = app::sky::ImportJob { photo, out, ground, sun_azimuth_deg: sun_azimuth, clamp_negative };
            let r = app::sky::import(&job)?;
            r.notes.iter().for_each(|n| eprintln!("{n}"));
            eprintln!("wrote {} ({} x {})", job.out.display(), r.width, r.height);
        }
        SkyCommand::Info { file, json } => {
            let info = app::sky::info(&file)?;
            if json {
                emit(&info, true)?;
            } else {
                emit(&format!("{}: {info}", file.display()), false)?;
            }
        }
        #[rustfmt::skip]
        SkyCommand::Sheet { files, thumb_width, columns, out } => {
            let (w, h) = app::sky::sheet(&files, thumb_width, columns, &out)?;
            eprintln!("wrote {} ({w} x {h})", out.display());
        }
    }
    Ok(())
}
