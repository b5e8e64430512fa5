//! Light transport shared by both passes: where a ray meets a surface (`hit`), the specular rules of
//! mirrors and glass (`scatter`, with the pure formulas in `optics`), choosing points on the emitters
//! (`emitters`, near ones by solid angle: `solid_angle`), rays through cut-out textures (`cut_outs`), the photons traced once per run from the
//! emitters through specular surfaces (`photons`), and the normals a diffuse point is shaded with
//! (`shading`). Pass one (radiosity) and pass two (trace) both read from here; nothing here reads
//! from either pass.

pub mod cut_outs;
pub mod emitter_polygon;
pub mod emitters;
pub mod hit;
pub mod optics;
pub mod photons;
pub mod ray_stack;
pub mod scatter;
pub mod shading;
pub mod solid_angle;

pub use hit::SurfaceHit;
pub use photons::Photons;
pub use scatter::Scatter;
pub use shading::SurfaceNormals;
