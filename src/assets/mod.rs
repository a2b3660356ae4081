//! What scenes and materials read from files beside them: images (decoded once, and how a surface
//! reads one), textures, normal maps, alpha, environments, and the record of every input file
//! a render reads (for film identities), and the loader that reads them for a scene file. Below materials, which take these as parameters, and
//! below the scene, which loads them.

pub mod alpha;
pub mod environment;
pub mod image;
pub mod image_lookup;
pub mod inputs;
pub mod loader;
pub mod normal_map;
pub mod texture;
