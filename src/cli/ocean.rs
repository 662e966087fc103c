//! `ocean`: the sea state's flags.

use std::path::PathBuf;

use vastocean::app;
use vastocean::ocean::{LayerSpec, OceanParams};

#[derive(clap::Args)]
// Negative numbers are values, so that `--wind -1` reaches validation and its named error.
#[command(allow_negative_numbers = true)]
pub struct OceanArgs {
    /// Wind speed at 10 m, m/s.
    #[arg(long, default_value_t = OceanParams::default().wind_speed)]
    wind: f64,
    /// Fetch, km.
    #[arg(long, default_value_t = OceanParams::default().fetch_km)]
    fetch: f64,
    /// Water depth, m.
    #[arg(long, default_value_t = OceanParams::default().depth_m)]
    depth: f64,
    /// Scale the realization to this RMS height, m (the paper's Table 1 gives one per case).
    #[arg(long)]
    rms: Option<f64>,
    /// Layers as SIZE_M:N pairs, coarsest first, e.g. 400:512,47.3:512,5.83:256.
    #[arg(long, value_parser = parse_layers)]
    layers: Option<Layers>,
    /// Horizontal displacement scale (paper eq. 3's f_d with the crest-sharpening sign); 0 =
    /// pure height field.
    #[arg(long, default_value_t = OceanParams::default().choppiness)]
    choppiness: f64,
    /// Time t of paper eq. 2, s.
    #[arg(long, default_value_t = 0.0)]
    time: f64,
    /// Random seed of the realization.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write a height / shaded-normal preview PNG here.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Preview extent, metres (default: the coarsest layer's size).
    #[arg(long)]
    png_extent: Option<f64>,
    #[arg(long)]
    pub json: bool,
}

/// A newtype so clap treats the whole list as one value.
#[derive(Clone, Debug)]
pub struct Layers(Vec<LayerSpec>);

fn parse_layers(s: &str) -> Result<Layers, String> {
    let layer = |pair: &str| {
        let (size, n) = pair
            .split_once(':')
            .ok_or_else(|| format!("layer {pair:?} is not SIZE_M:N"))?;
        let size_m = size
            .trim()
            .parse::<f64>()
            .map_err(|e| format!("layer size {size:?}: {e}"))?;
        let n = n
            .trim()
            .parse::<usize>()
            .map_err(|e| format!("layer grid {n:?}: {e}"))?;
        Ok(LayerSpec { size_m, n })
    };
    s.split(',')
        .map(layer)
        .collect::<Result<_, String>>()
        .map(Layers)
}

impl OceanArgs {
    pub fn job(&self) -> app::ocean::OceanJob {
        let defaults = OceanParams::default();
        app::ocean::OceanJob {
            params: OceanParams {
                wind_speed: self.wind,
                fetch_km: self.fetch,
                depth_m: self.depth,
                rms_m: self.rms,
                choppiness: self.choppiness,
                time_s: self.time,
                layers: self.layers.clone().map_or(defaults.layers.clone(), |l| l.0),
                ..defaults
            },
            seed: self.seed,
            png: self.png.clone().map(|p| (p, self.png_extent)),
        }
    }
}
