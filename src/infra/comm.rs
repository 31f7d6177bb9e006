//! The processes of a run: one without MPI, `mpirun -n N` of them with the `mpi` feature.
//!
//! Every collective here is deterministic for a given number of ranks: a sum gathers each
//! rank's values and adds them in rank order on every rank, so all ranks hold the same bits
//! and a rerun gives them again. Nothing depends on message arrival order.

use crate::infra::decomposition::Split;
use std::sync::atomic::{AtomicU64, Ordering};
#[cfg(feature = "mpi")]
use std::sync::Mutex;

/// The processes of a run, and the collectives the decomposition needs.
pub struct Comm {
    rank: usize,
    size: usize,
    /// Bytes this rank has sent to others (exchanges and its part of the gathers).
    sent: AtomicU64,
    /// How the ranks are to be laid over a grid, when asked ([`Comm::with_layout`]).
    layout: Option<Split>,
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
            layout: None,
            #[cfg(feature = "mpi")]
            mpi: None,
        }
    }

    /// How many processes the launcher started when more than one: what `mpirun` (Open MPI)
    /// or `srun` (PMI) tell each process, read without starting MPI.
    pub fn launched() -> Option<usize> {
        ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
            .iter()
            .filter_map(|v| std::env::var(v).ok())
            .find_map(|n| n.parse::<usize>().ok().filter(|&n| n > 1))
    }

    /// This process's rank among those the launcher started, read as [`Comm::launched`].
    pub fn launched_rank() -> Option<usize> {
        ["OMPI_COMM_WORLD_RANK", "PMI_RANK"]
            .iter()
            .find_map(|v| std::env::var(v).ok()?.parse().ok())
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
                layout: None,
                mpi: Some(Mpi {
                    world: Mutex::new(world),
                    _universe: universe,
                }),
            })
        }
        #[cfg(not(feature = "mpi"))]
        {
            // Started by mpirun or srun but built without MPI: every process would run the
            // whole scene on its own.
            if let Some(n) = Comm::launched() {
                return Err(format!(
                    "started as one of {n} MPI processes, but this kdmpm was built without \
                     MPI: build it with `cargo build --release --features mpi`"
                ));
            }
            Ok(Comm::single())
        }
    }

    /// These ranks, to be laid over a grid as `layout[0]` slabs cut `layout[1]` times
    /// across ([`crate::infra::decomposition`]), as MPI's Cartesian communicators carry their
    /// dimensions; refused unless the parts are as many as the ranks.
    pub fn with_layout(mut self, layout: Split) -> Result<Comm, String> {
        if layout[0] == 0 || layout[1] == 0 || layout[0] * layout[1] != self.size {
            return Err(format!(
                "--split {}x{} lays {} parts, but the run has {} rank(s): the slabs times the \
                 cuts across must be the rank count (mpirun -n {})",
                layout[0],
                layout[1],
                layout[0] * layout[1],
                self.size,
                layout[0] * layout[1]
            ));
        }
        self.layout = Some(layout);
        Ok(self)
    }

    /// The layout asked for with [`Comm::with_layout`], if any.
    pub fn layout(&self) -> Option<Split> {
        self.layout
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

    /// The lowest rank's message among those given, with that rank, on every rank: what a
    /// collective step that failed on some ranks reports (rank 0 speaks for all). `None`
    /// when no rank has one.
    pub fn first_message(&self, mine: Option<&str>) -> Option<(usize, String)> {
        if self.size == 1 {
            return mine.map(|m| (0, m.to_string()));
        }
        // Lengths first (+1: an empty message is still one), then the texts padded to the
        // longest, one byte a word (exact in f64).
        let lengths = self.gather_all(&[mine.map_or(0.0, |m| m.len() as f64 + 1.0)]);
        let from = lengths.iter().position(|&l| l > 0.0)?;
        let width = lengths.iter().fold(0.0f64, |a, &b| a.max(b)) as usize;
        let mut padded = vec![0.0; width];
        for (w, b) in padded.iter_mut().zip(mine.unwrap_or_default().bytes()) {
            *w = b as f64;
        }
        let all = self.gather_all(&padded);
        let len = lengths[from] as usize - 1;
        let bytes: Vec<u8> = all[from * width..from * width + len]
            .iter()
            .map(|&b| b as u8)
            .collect();
        Some((from, String::from_utf8_lossy(&bytes).into_owned()))
    }

    /// [`Comm::first_message`] of every rank's `result`: the lowest failing rank and its
    /// error, as text, on every rank.
    pub fn first_error<T, E: std::fmt::Display>(&self, result: &Result<T, E>) -> Option<(usize, String)> {
        let mine = result.as_ref().err().map(|e| e.to_string());
        self.first_message(mine.as_deref())
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

    /// The correctly rounded sum of every rank's `values`: the same bits whatever the rank
    /// count and the order of the values (an exact sum, rounded once).
    pub fn exact_sum(&self, values: impl IntoIterator<Item = f64>) -> f64 {
        let mut mine = ExactSum::default();
        values.into_iter().for_each(|v| mine.add(v));
        if self.size == 1 {
            return mine.total();
        }
        let mut len = [mine.partials.len() as f64];
        self.max(&mut len);
        let mut padded = mine.partials.clone();
        padded.resize(len[0] as usize, 0.0);
        let mut all = ExactSum::default();
        self.gather_all(&padded).into_iter().for_each(|v| all.add(v));
        all.total()
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

/// An exact sum of doubles as non-overlapping partial sums (Shewchuk 1997, "Adaptive
/// precision floating-point arithmetic", as Python's `math.fsum`), rounded once at the end.
#[derive(Clone, Debug, Default)]
pub struct ExactSum {
    partials: Vec<f64>,
}

impl ExactSum {
    /// Adds `x` exactly.
    pub fn add(&mut self, mut x: f64) {
        let mut kept = 0;
        for j in 0..self.partials.len() {
            let mut y = self.partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                self.partials[kept] = lo;
                kept += 1;
            }
            x = hi;
        }
        self.partials.truncate(kept);
        self.partials.push(x);
    }

    /// The sum, correctly rounded.
    pub fn total(&self) -> f64 {
        let mut p = self.partials.clone();
        let Some(mut hi) = p.pop() else {
            return 0.0;
        };
        let mut lo = 0.0;
        while let Some(y) = p.pop() {
            let x = hi;
            hi = x + y;
            lo = y - (hi - x);
            if lo != 0.0 {
                break;
            }
        }
        // Round half to even across the partials left: the next one breaks a tie.
        if let Some(&next) = p.last() {
            if (lo < 0.0 && next < 0.0) || (lo > 0.0 && next > 0.0) {
                let y = lo * 2.0;
                let x = hi + y;
                if y == x - hi {
                    hi = x;
                }
            }
        }
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exact_sum_does_not_depend_on_the_order_of_its_values() {
        let values: Vec<f64> = (0..1000)
            .map(|i| 1.0 / (i as f64 + 0.37) * if i % 3 == 0 { -1e8 } else { 1.0 })
            .collect();
        let sum = |v: &[f64]| {
            let mut s = ExactSum::default();
            v.iter().for_each(|&x| s.add(x));
            s.total()
        };
        let mut reversed = values.clone();
        reversed.reverse();
        assert_eq!(sum(&values).to_bits(), sum(&reversed).to_bits());
        assert_eq!(sum(&[1e100, 1.0, -1e100]), 1.0);
        assert_eq!(sum(&[0.1; 10]), 1.0);
    }

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
