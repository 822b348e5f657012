//! # pdw-soa — planar spatial operator algebra kernel
//!
//! Planar serial chains (revolute and prismatic joints, base to tip) in the spatial operator
//! algebra of the seed thesis §3.3: 3-component motion vectors `[ω, v_y, v_z]`, force vectors
//! `[τ, f_y, f_z]`, the rigid-body transform Φ (eq. 3.10), joint maps H (eq. 3.4–3.5), spatial
//! inertias M_k (eq. 3.16 plus a rotational inertia about the COM), gravity as the base
//! acceleration (eq. 3.12). See [`chain`] for the conventions and [`spatial`] for the algebra.
//!
//! The model ([`Chain`]) is immutable; a [`Workspace`] sized from it holds every intermediate;
//! algorithms are free functions, one per file.
//!
//! # Memory: what allocates
//! The caller owns all scratch and sizes it once from the chain: [`Workspace::new`]`(&chain)`
//! for the scalar kernels (vectors of length `n = chain.dof()` and `n × n` dense blocks),
//! [`BatchWorkspace::new`]`(&chain, lanes)` for the batched ones (`n` columns of one block of
//! lanes; any lane count is processed block by block). What building them allocates is known
//! before, byte for byte ([`Workspace::scratch_bytes`]`(n)`,
//! [`BatchWorkspace::scratch_bytes`]`(n, lanes)`, in the manner of faer's `*_scratch` queries;
//! e.g. 4 125 bytes for `n = 5`, and 201 408 for 256 or more lanes of it, per thread).
//! Reused, they make these calls
//! allocation-free from the second call on (tested with a counting global allocator in
//! `tests/derivatives.rs`): [`forward_kinematics`], [`aba()`], [`rnea()`],
//! [`forward_dynamics_crba`], [`total_energy`], [`batch_aba()`], [`batch_rnea()`]. The first
//! batched call of a process reads the `PDW_SIMD` override once (pdw-simd caches the path).
//! The dual-number [`derivatives`] need no workspace: their intermediates are stack arrays of
//! [`derivatives::MAX_DOF`] entries, so every call is allocation-free, and chains of more than
//! `MAX_DOF` joints are refused with [`SoaError::DimensionMismatch`].

pub mod aba;
pub mod batch;
pub mod batch_aba;
pub mod batch_rnea;
pub mod chain;
pub mod closed_chain;
pub mod crba;
pub mod derivatives;
pub mod dual;
pub mod energy;
pub mod error;
pub mod impact;
pub mod kinematics;
pub mod naive;
pub mod pseudo_joint;
pub mod rnea;
pub mod spatial;
pub mod unilateral;
pub mod workspace;

pub use aba::{aba, aba_masked};
pub use batch::BatchWorkspace;
pub use batch_aba::{batch_aba, batch_aba_view};
pub use batch_rnea::batch_rnea;
pub use chain::{Chain, ChainBuilder, JointKind, Link};
pub use closed_chain::{closed_chain_dynamics, ClosedChainForces};
pub use crba::{crba, forward_dynamics_crba};
pub use derivatives::{
    aba_derivatives, contact_impact, joint_lock_impact_derivatives, rolling_base_derivatives,
    rolling_base_dynamics, tip_impact_derivatives, tip_position_derivatives,
};
pub use dual::{Dual, Scalar};
pub use energy::{
    angular_momentum_about, kinetic_energy, linear_momentum, potential_energy, total_energy,
};
pub use error::SoaError;
pub use impact::{impulsive_constraint, joint_lock_impact, tip_impact};
pub use kinematics::{
    forward_kinematics, inverse_kinematics, pseudo_inverse_rates, tip_acceleration, tip_jacobian,
    tip_jacobian_linear, tip_position, tip_velocity,
};
pub use naive::{naive_forward_dynamics, naive_mass_matrix, NaiveWorkspace};
pub use pseudo_joint::pseudo_joint_dynamics;
pub use rnea::{base_reaction, bias_forces, rnea};
pub use unilateral::{unilateral_impact, ImpactItem, ImpactRow, ImpactSolution, ItemResult};
pub use workspace::Workspace;
