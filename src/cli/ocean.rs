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
    /// Without it, --hs or a preset, the default scene's 0.225 m, as `render` has it.
    #[arg(long, conflicts_with = "hs")]
    rms: Option<f64>,
    /// Scale the realization to this significant wave height Hs = 4 x RMS, m.
    #[arg(long)]
    hs: Option<f64>,
    /// Peak period of the wind sea, s, instead of the fetch law's (with --hs or --rms).
    #[arg(long)]
    tp: Option<f64>,
    /// JONSWAP peak enhancement gamma of the wind sea.
    #[arg(long, default_value_t = OceanParams::default().gamma)]
    gamma: f64,
    #[command(flatten)]
    sea: super::SeaFlags,
    /// Direction the wind blows towards, degrees from +x towards +z.
    #[arg(long, default_value_t = OceanParams::default().wind_dir_deg)]
    wind_dir: f64,
    /// Layers as SIZE_M:N pairs, coarsest first, e.g. 400:512,47.3:512,5.83:256, or `auto` to
    /// choose them from the sea's peak wavelength (docs/ocean.md).
    #[arg(long, value_parser = parse_layers, allow_hyphen_values = true)]
    layers: Option<Layers>,
    /// How the layers share the wavenumbers: overlap (each band in several layers, so the sum
    /// does not tile) or disjoint (each layer its own band, the earlier scheme).
    #[arg(long, value_parser = super::choice::<vastocean::ocean::Layering>(), default_value_t = OceanParams::default().layering)]
    layering: vastocean::ocean::Layering,
    /// Cap Mitsuyasu's spreading exponent (Goda: 10 wind sea, 25/75 short/long-travelled swell).
    #[arg(long)]
    spreading_cap: Option<f64>,
    /// Horizontal displacement scale (paper eq. 3's f_d with the crest-sharpening sign); 0 =
    /// pure height field.
    #[arg(long, default_value_t = OceanParams::default().choppiness)]
    choppiness: f64,
    /// How the surface is read between grid points (what the mapped normals and the reported
    /// "as read" slopes use).
    #[arg(long, value_parser = super::choice::<vastocean::ocean::Interp>(), default_value_t = OceanParams::default().interp)]
    interp: vastocean::ocean::Interp,
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
    /// Preview size: each of its two panels (height, shaded normals) is PX x PX pixels.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=8192), requires = "png")]
    png_size: u32,
    /// Sample the surface along a line X0,Z0,X1,Z1,N (world metres, N points) into --csv: x, z,
    /// h, Dx, Dz and the normal, to check the repeat correlation independently.
    #[arg(long, value_parser = parse_profile, requires = "csv", allow_hyphen_values = true)]
    profile: Option<([f64; 2], [f64; 2], usize)>,
    /// Where --profile writes its CSV.
    #[arg(long, requires = "profile")]
    csv: Option<PathBuf>,
    /// Split the mean square slope as `--normals filtered` does for a pixel footprint W metres
    /// wide on the sea (the default filter width, a Gaussian of std W / sqrt 12): what the
    /// mapped normals resolve and what the rough lobe takes, per layer (the sea's slopes, the
    /// `smith` lobe's split; the default `mapped` lobe splits the slopes as read the same way).
    #[arg(long, value_name = "W")]
    footprint: Option<f64>,
    /// Print the result as one JSON object on stdout instead of the report.
    #[arg(long)]
    pub json: bool,
}

impl OceanArgs {
    /// The sea-state keys these flags set, each with its flag (every one has a value here, typed
    /// or default), so that errors name the flag ([`super::name_flags`]).
    pub fn given(&self) -> Vec<(&'static str, &'static str)> {
        vec![
            ("ocean.wind_speed", "--wind"),
            ("ocean.fetch_km", "--fetch"),
            ("ocean.depth_m", "--depth"),
            ("ocean.rms_m", "--rms"),
            ("ocean.hs_m", "--hs"),
            ("ocean.tp_s", "--tp"),
            ("ocean.gamma", "--gamma"),
            ("ocean.beaufort", "--beaufort"),
            ("ocean.douglas", "--douglas"),
            ("ocean.swell", "--swell"),
            ("ocean.wind_dir_deg", "--wind-dir"),
            ("ocean.spreading_cap", "--spreading-cap"),
            ("ocean.choppiness", "--choppiness"),
            ("ocean.time_s", "--time"),
        ]
    }
}

/// A newtype so clap treats the whole list as one value.
#[derive(Clone, Debug)]
pub struct Layers(Vec<LayerSpec>);

fn parse_profile(s: &str) -> Result<([f64; 2], [f64; 2], usize), String> {
    let bad = || format!("a profile is X0,Z0,X1,Z1,N, e.g. 0,0,2000,0,2001 (got `{s}`)");
    let v: Vec<&str> = s.split(',').map(str::trim).collect();
    if v.len() != 5 {
        return Err(bad());
    }
    let f = |i: usize| v[i].parse::<f64>().map_err(|_| bad());
    let n = v[4].parse::<usize>().map_err(|_| bad())?;
    Ok(([f(0)?, f(1)?], [f(2)?, f(3)?], n))
}

fn parse_layers(s: &str) -> Result<Layers, String> {
    if s.trim() == "auto" {
        return Ok(Layers(Vec::new()));
    }
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
        let mut params = OceanParams {
            wind_speed: self.wind,
            fetch_km: self.fetch,
            depth_m: self.depth,
            // the default scene's height target, as `render` has it, unless a height or a
            // preset says otherwise
            rms_m: if self.rms.is_some()
                || self.hs.is_some()
                || self.sea.beaufort.is_some()
                || self.sea.douglas.is_some()
            {
                self.rms
            } else {
                defaults.rms_m
            },
            hs_m: self.hs,
            tp_s: self.tp,
            gamma: self.gamma,
            beaufort: self.sea.beaufort,
            douglas: self.sea.douglas,
            swell: self.sea.swell.clone(),
            wind_dir_deg: self.wind_dir,
            choppiness: self.choppiness,
            time_s: self.time,
            layers: self.layers.clone().map_or(defaults.layers.clone(), |l| l.0),
            layering: self.layering,
            spreading_cap: self.spreading_cap,
            interp: self.interp,
            ..defaults
        };
        params.apply_preset();
        // a preset's sea chooses its layers unless --layers names them
        params.layers_auto |= params.preset().is_some() && self.layers.is_none();
        params.resolve_layers();
        app::ocean::OceanJob {
            params,
            seed: self.seed,
            png: self
                .png
                .clone()
                .map(|p| (p, self.png_extent, self.png_size)),
            profile: match (&self.profile, &self.csv) {
                (Some((from, to, n)), Some(csv)) => Some((csv.clone(), *from, *to, *n)),
                _ => None,
            },
            footprint_m: self.footprint,
        }
    }
}
