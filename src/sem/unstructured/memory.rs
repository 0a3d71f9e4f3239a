//! The memory variables of viscoelastic elements on an unstructured mesh
//! ([`crate::attenuation`]): each lane group of elements with a viscoelastic element keeps
//! one [`GroupMemory`], every lane with its own material's relaxation turned by the element's
//! angle (a turned ply's relaxation couples normal and shear strain); the element kernel
//! updates it in the explicit step ([`Viscous`](crate::attenuation::memory::Viscous)) and the
//! passes here start it and probe it for the ledger. Groups of elastic elements keep none and
//! run the elastic kernel.

use super::kernel::UnstructuredWorkspace;
use super::{GroupMemory, UnstructuredSem, LANES};
use crate::attenuation::memory::{Probe, Start};
use crate::error::{Error, Result};
use crate::material::{Material, Relaxation};

impl UnstructuredSem {
    /// The shortest relaxation time of the elements' materials (s); `None` where all are
    /// elastic.
    pub fn shortest_relaxation_s(&self) -> Option<f64> {
        crate::material::shortest_relaxation_s(&self.materials)
    }

    /// Zero memory variables for the lane groups holding a viscoelastic element, at step `dt`,
    /// eps_{-1} from `u_prev` (see [`crate::solve::Discretisation::start_memory`]); none where
    /// every element is elastic.
    pub(crate) fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut UnstructuredWorkspace) {
        work.memory.clear();
        if self.shortest_relaxation_s().is_none() {
            return;
        }
        let points = (self.order + 1) * (self.order + 1);
        work.memory = (0..self.elements.div_ceil(LANES))
            .map(|group| {
                let turned: [Option<Relaxation>; LANES] = std::array::from_fn(|lane| {
                    let quad = self.mesh.elements.get(group * LANES + lane)?;
                    let material = &self.materials[quad.material];
                    material.relaxation.as_ref()?;
                    material.rotated(quad.angle_rad).relaxation
                });
                GroupMemory::by_lane(turned.each_ref().map(Option::as_ref), points, dt)
            })
            .collect();
        self.memory_pass::<Start>(u_prev, work);
    }

    /// The energy dissipated since the last call: dt times the groups' sums, in group order
    /// (bit-identical for any thread count).
    pub(crate) fn take_viscous_loss(&self, work: &mut UnstructuredWorkspace) -> f64 {
        work.memory
            .iter_mut()
            .flatten()
            .map(GroupMemory::take_loss)
            .sum()
    }

    /// MEM_{n-1/2} ([`crate::attenuation::memory`]) from u_n = `u`, the memory left as it was.
    pub(crate) fn memory_energy(&self, u: &[f64], work: &mut UnstructuredWorkspace) -> f64 {
        if work.memory.is_empty() {
            return 0.0;
        }
        work.memory
            .iter_mut()
            .flatten()
            .for_each(GroupMemory::clear_energy);
        self.memory_pass::<Probe>(u, work);
        work.memory.iter().flatten().map(GroupMemory::energy).sum()
    }
}

/// The viscoelastic materials share their relaxation times (a lane group's memory updates
/// every lane with one set), else an error naming `materials` and the first that differs.
pub(super) fn check_shared_relaxation_times(materials: &[Material]) -> Result<()> {
    let mut viscous = materials.iter().filter(|m| m.relaxation.is_some());
    let Some(first) = viscous.next() else {
        return Ok(());
    };
    let tau = |m: &Material| m.relaxation.as_ref().map(|r| r.tau_s.clone());
    match viscous.find(|m| tau(m) != tau(first)) {
        Some(m) => Err(Error::invalid(
            "materials",
            &m.name,
            format!(
                "relaxes with times {:?} s where {} relaxes with {:?} s: the viscoelastic \
                 materials of one mesh share their relaxation times (one band, one count of \
                 mechanisms)",
                tau(m).unwrap_or_default(),
                first.name,
                tau(first).unwrap_or_default()
            ),
        )),
        None => Ok(()),
    }
}
