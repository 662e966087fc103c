//! Rendering (paper section 5): cameras, the water interface, the path tracer with Fresnel
//! branching and normal mapping, the film that turns paths into pixels, and the pipeline that
//! runs a scene from ocean to image. The sky light lives in [`crate::sky`].

pub mod aov;
mod bsdf;
pub mod camera;
mod camera_paths;
pub mod counters;
pub mod dielectric;
pub mod earth_tilt;
pub mod film;
pub mod footprint;
pub mod ggx;
pub mod integrator;
mod interface;
mod limits;
pub mod microfacet;
mod normals;
mod objects;
pub mod pipeline;
pub mod pixel_state;
pub mod report;
pub mod shortcuts;
mod slots;
pub mod strata;
pub mod water;

pub use crate::config::{NormalMode, Projection, Water};
pub use crate::sky::{AnalyticSky, Sky};
pub use bsdf::MAX_SUN_SAMPLES;
pub use camera::Camera;
pub use film::{render_image, render_image_samples};
pub use integrator::{Counters, SceneRef, TraceSettings};
