//! Collectives over MPI ranks (`cargo test --release --features mpi --test mpi`; needs the
//! system's MPI, see the README). Each test starts this test binary again under
//! `mpirun -n N`, which runs the `ranks_*` body on every rank; the ranks' exit codes are
//! the verdict.
#![cfg(feature = "mpi")]

use kdmpm::comm::Comm;
use kdmpm::decomposition::Decomposition;
use std::process::Command;

/// Set in the ranks that `mpirun` starts.
const CHILD: &str = "KDMPM_MPI_TEST_CHILD";

/// Runs the test `name` of this binary on `ranks` ranks and checks every rank passed.
fn on_ranks(name: &str, ranks: usize) {
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
        .arg(exe)
        .args([name, "--exact", "--nocapture", "--test-threads", "1"])
        .env(CHILD, "1")
        .output()
        .expect("mpirun starts (install openmpi-bin, see the README)");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.matches("1 passed").count() == ranks,
        "{name} on {ranks} ranks:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn child() -> bool {
    std::env::var_os(CHILD).is_some()
}

/// The collectives on every rank: sums in rank order (the same bits everywhere), the
/// largest value, a NaN that must not hide, `any`, and an exchange with both neighbours.
#[test]
fn ranks_agree_on_sums_maxima_and_exchanges() {
    if !child() {
        for n in [1, 2, 4] {
            on_ranks("ranks_agree_on_sums_maxima_and_exchanges", n);
        }
        return;
    }
    let comm = Comm::world().expect("MPI starts");
    let (r, n) = (comm.rank(), comm.size());
    // Values whose sum depends on the order of the additions.
    let mine = [
        1e16 * (r % 2) as f64 - 1e16 * ((r + 1) % 2) as f64 + r as f64,
        0.1 * (r + 1) as f64,
    ];
    let mut sum = mine;
    comm.sum(&mut sum);
    let all = comm.gather_all(&mine);
    let in_order: Vec<f64> = (0..2)
        .map(|i| (1..n).fold(all[i], |a, q| a + all[q * 2 + i]))
        .collect();
    assert_eq!(
        sum.map(f64::to_bits).to_vec(),
        in_order.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    // Every rank holds the same bits: rank 0's, gathered.
    let everyone = comm.gather_all(&sum);
    assert!(everyone
        .chunks(2)
        .all(|c| c[0].to_bits() == sum[0].to_bits() && c[1].to_bits() == sum[1].to_bits()));
    let mut largest = [r as f64];
    comm.max(&mut largest);
    assert_eq!(largest[0], (n - 1) as f64);
    let mut nan = [if r == n - 1 { f64::NAN } else { 1.0 }];
    comm.max(&mut nan);
    assert!(nan[0].is_nan());
    assert!(comm.any(r == 0));
    assert!(!comm.any(false));
    // Up the ranks, then down, messages of the sender's rank + 1 values.
    let up = comm.exchange(
        (r + 1 < n).then_some(r + 1),
        &vec![r as f64; r + 1],
        r.checked_sub(1),
    );
    if r > 0 {
        assert_eq!(up, vec![(r - 1) as f64; r]);
    }
    let down = comm.exchange(
        r.checked_sub(1),
        &vec![r as f64; r + 1],
        (r + 1 < n).then_some(r + 1),
    );
    if r + 1 < n {
        assert_eq!(down, vec![(r + 1) as f64; r + 2]);
    }
}

/// Every rank finds the same decomposition from the same counts.
#[test]
fn ranks_find_the_same_decomposition() {
    if !child() {
        on_ranks("ranks_find_the_same_decomposition", 4);
        return;
    }
    let comm = Comm::world().expect("MPI starts");
    let counts: Vec<u64> = (0..45).map(|c| 180 - 4 * c).collect();
    let d = Decomposition::balanced(&counts, comm.size(), comm.rank(), 3).expect("splits");
    let bounds: Vec<f64> = d.bounds.iter().map(|&b| b as f64).collect();
    let all = comm.gather_all(&bounds);
    assert!(all.chunks(bounds.len()).all(|b| b == &bounds[..]), "{all:?}");
    assert_eq!(d.rank, comm.rank());
}
