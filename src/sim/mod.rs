//! The simulated cell: the physical world the simulated devices share (a
//! cable between two supports, where the arm and the jaws are), the
//! cable's and the tactile pad's physics, and the arm's motion timing. The
//! devices themselves live beside their traits in `hw/`. The model and its
//! parameters: docs/simulated-cell.md.

pub mod cable;
pub mod motion;
pub mod render;
pub mod tactile_model;
pub mod world;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Independent random streams, one per simulated source, so that one
/// device drawing more numbers does not change what another draws.
#[derive(Debug, Clone, Copy)]
pub enum Stream {
    Arm = 1,
    Tactile = 2,
    TactileCalibration = 3,
    Detector = 4,
    /// A campaign trial's perturbation.
    Perturbation = 5,
    Camera = 6,
}

/// The random stream `stream` of a cell seeded with `seed`.
pub fn rng(seed: u64, stream: Stream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream as u64);
    rng
}
