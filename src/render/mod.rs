//! Rendering (paper section 5): cameras, image-based sky light, the water interface, the path
//! tracer with Fresnel branching and normal mapping, and the film that turns paths into pixels.

pub mod camera;
pub mod film;
pub mod integrator;
pub mod pipeline;
pub mod sky;
pub mod sky_gen;
pub mod sky_tools;
pub mod water;

pub use camera::{Camera, Projection};
pub use film::render_image;
pub use integrator::{Counters, NormalMode, SceneRef, TraceSettings};
pub use sky::{AnalyticSky, Sky, SkySource};
pub use water::Water;
