//! The processes of a run: one without MPI, `mpirun -n N` of them with the `mpi` feature.
//!
//! Every collective here is deterministic for a given number of ranks: a sum gathers each
//! rank's values and adds them in rank order on every rank, so all ranks hold the same bits
//! and a rerun gives them again. Nothing depends on message arrival order.

use std::sync::atomic::{AtomicU64, Ordering};
#[cfg(feature = "mpi")]
use std::sync::Mutex;

/// The processes of a run, and the collectives the decomposition needs.
pub struct Comm {
    rank: usize,
    size: usize,
    /// Bytes this rank has sent to others (exchanges and its part of the gathers).
    sent: AtomicU64,
    #[cfg(feature = "mpi")]
    mpi: Option<Mpi>,
}

/// The MPI world, with the universe that finalises MPI when dropped.
#[cfg(feature = "mpi")]
struct Mpi {
    world: Mutex<mpi::topology::SimpleCommunicator>,
    // Dropped after `world`: fields drop in order of declaration.
    _universe: mpi::environment::Universe,
}

// SAFETY: MPI is initialised with MPI_THREAD_SERIALIZED (`Comm::world`), which allows MPI
// calls from any thread as long as no two overlap; every call goes through the `Mutex`,
// which makes them one at a time. The communicator handle is a plain value MPI owns.
#[cfg(feature = "mpi")]
unsafe impl Send for Mpi {}
// SAFETY: as for `Send`: shared access only ever reaches MPI through the `Mutex`.
#[cfg(feature = "mpi")]
unsafe impl Sync for Mpi {}

impl std::fmt::Debug for Comm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Comm(rank {} of {})", self.rank, self.size)
    }
}

impl Default for Comm {
    fn default() -> Self {
        Comm::single()
    }
}

impl Comm {
    /// One process.
    pub fn single() -> Comm {
        Comm {
            rank: 0,
            size: 1,
            sent: AtomicU64::new(0),
            #[cfg(feature = "mpi")]
            mpi: None,
        }
    }

    /// The processes `mpirun` started; one process when started without it, or when the
    /// build has no `mpi` feature. Call once, before any thread pool is built.
    pub fn world() -> Result<Comm, String> {
        #[cfg(feature = "mpi")]
        {
            use mpi::environment::Threading;
            use mpi::topology::Communicator;
            let (universe, level) = mpi::initialize_with_threading(Threading::Serialized)
                .ok_or_else(|| "MPI is already initialised".to_string())?;
            if level < Threading::Serialized {
                return Err(format!(
                    "the MPI library offers thread level {level:?}; kdmpm calls MPI from its \
                     stepping thread and needs Serialized"
                ));
            }
            let world = universe.world();
            let (rank, size) = (world.rank() as usize, world.size() as usize);
            Ok(Comm {
                rank,
                size,
                sent: AtomicU64::new(0),
                mpi: Some(Mpi {
                    world: Mutex::new(world),
                    _universe: universe,
                }),
            })
        }
        #[cfg(not(feature = "mpi"))]
        Ok(Comm::single())
    }

    /// This process's rank, from 0.
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// The number of ranks.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Bytes this rank has sent to the others so far: its values in every gather (once for
    /// each other rank) and its exchanges.
    pub fn sent_bytes(&self) -> u64 {
        self.sent.load(Ordering::Relaxed)
    }

    /// True on rank 0, which writes the run's shared files.
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// Every rank's `values`, in rank order: `ranks[r]` are rank r's. The slices must be
    /// as long on every rank.
    pub fn gather_all(&self, values: &[f64]) -> Vec<f64> {
        #[cfg(feature = "mpi")]
        if let Some(m) = &self.mpi {
            use mpi::collective::CommunicatorCollectives;
            let bytes = 8 * values.len() * (self.size - 1);
            self.sent.fetch_add(bytes as u64, Ordering::Relaxed);
            let mut all = vec![0.0; values.len() * self.size];
            let world = m.world.lock().expect("MPI calls never panic midway");
            world.all_gather_into(values, &mut all[..]);
            return all;
        }
        values.to_vec()
    }

    /// Element-wise sums of `values` over the ranks, added in rank order on every rank.
    pub fn sum(&self, values: &mut [f64]) {
        self.combine(values, |a, b| a + b);
    }

    /// Element-wise largest `values` over the ranks (a NaN on any rank wins: it must not
    /// hide).
    pub fn max(&self, values: &mut [f64]) {
        self.combine(values, |a, b| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        });
    }

    /// True on every rank when `flag` is true on any.
    pub fn any(&self, flag: bool) -> bool {
        let mut v = [if flag { 1.0 } else { 0.0 }];
        self.max(&mut v);
        v[0] > 0.0
    }

    fn combine(&self, values: &mut [f64], op: impl Fn(f64, f64) -> f64) {
        if self.size == 1 {
            return;
        }
        let n = values.len();
        let all = self.gather_all(values);
        for (i, v) in values.iter_mut().enumerate() {
            *v = (1..self.size).fold(all[i], |acc, r| op(acc, all[r * n + i]));
        }
    }

    /// Completes a list indexed by point id in which each rank filled its own points and
    /// left the others NaN (see [`crate::measure::positions`]): every rank gets every
    /// point's entry. The lists may differ in length (ids above a rank's last point).
    pub fn merge_by_id(&self, list: &mut Vec<[f64; 3]>) {
        if self.size == 1 {
            return;
        }
        let mut len = [list.len() as f64];
        self.max(&mut len);
        list.resize(len[0] as usize, [f64::NAN; 3]);
        let n = list.len() * 3;
        let all = self.gather_all(list.as_flattened());
        for (i, v) in list.as_flattened_mut().iter_mut().enumerate() {
            if let Some(found) = (0..self.size).map(|r| all[r * n + i]).find(|x| !x.is_nan()) {
                *v = found;
            }
        }
    }

    /// Sends `send` to rank `to` and receives what rank `from` sends this rank, of any
    /// length. Every rank calls it in the same pattern, so that sends meet receives.
    pub fn exchange(&self, to: Option<usize>, send: &[f64], from: Option<usize>) -> Vec<f64> {
        #[cfg(feature = "mpi")]
        if let Some(m) = &self.mpi {
            use mpi::point_to_point::{Destination, Source};
            use mpi::topology::Communicator;
            if to.is_some() {
                self.sent
                    .fetch_add(8 * (send.len() as u64 + 1), Ordering::Relaxed);
            }
            let world = m.world.lock().expect("MPI calls never panic midway");
            // Lengths first, then the values; a rank without a partner skips its half.
            let mut out = Vec::new();
            let len = [send.len() as u64];
            mpi::request::scope(|scope| {
                let sending = to.map(|to| {
                    let p = world.process_at_rank(to as i32);
                    (
                        p.immediate_send_with_tag(scope, &len[..], 1),
                        p.immediate_send_with_tag(scope, send, 2),
                    )
                });
                if let Some(from) = from {
                    let p = world.process_at_rank(from as i32);
                    let (n, _) = p.receive_with_tag::<u64>(1);
                    out = vec![0.0; n as usize];
                    p.receive_into_with_tag(&mut out[..], 2);
                }
                if let Some((a, b)) = sending {
                    a.wait();
                    b.wait();
                }
            });
            return out;
        }
        let _ = (to, from);
        send.to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_rank_leaves_its_values_as_they_are() {
        let c = Comm::single();
        let mut v = [1.5, -2.0, f64::NAN];
        c.sum(&mut v[..2]);
        assert_eq!(&v[..2], &[1.5, -2.0]);
        c.max(&mut v);
        assert!(v[2].is_nan());
        assert!(c.any(true) && !c.any(false));
        assert_eq!((c.rank(), c.size(), c.is_root()), (0, 1, true));
    }
}
