//! K-means timing for `scripts/bench-kmeans`: reads a clustered MPC table, standardises the
//! (delay, angle) features per position as `pradar cluster` does, runs linfa K-means
//! (k-means++, 10 restarts) for K = 2..=8 at every position, prints the wall time and
//! writes features and labels to a CSV for the scikit-learn side.
//!
//! Usage: cargo run --release --example kmeans_bench -- CLUSTERS.parquet OUT.csv

use pradar::cluster::kmeans_labels;
use std::io::Write;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        args.len() == 3,
        "usage: kmeans_bench CLUSTERS.parquet OUT.csv"
    );
    let mpcs = pradar::mpc::read_mpcs(std::path::Path::new(&args[1]))?;
    let np = mpcs.iter().map(|m| m.position + 1).max().unwrap_or(0);
    let mut sets = Vec::new();
    for p in 0..np {
        let ms: Vec<_> = mpcs.iter().filter(|m| m.position == p).collect();
        if ms.len() < 9 {
            continue;
        }
        let n = ms.len() as f64;
        let z = |v: Vec<f64>| {
            let mean = v.iter().sum::<f64>() / n;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n)
                .sqrt()
                .max(1e-12);
            v.into_iter().map(|x| (x - mean) / sd).collect::<Vec<_>>()
        };
        let d = z(ms.iter().map(|m| m.delay_ns).collect());
        let a = z(ms.iter().map(|m| m.angle_rel_deg).collect());
        sets.push((
            p,
            d.iter()
                .zip(&a)
                .map(|(x, y)| [*x, *y])
                .collect::<Vec<[f64; 2]>>(),
        ));
    }
    let t = Instant::now();
    let mut out = Vec::new();
    for (p, x) in &sets {
        for k in 2..=8usize {
            out.push((*p, k, kmeans_labels(x, k, 1 + k as u64, 10)?));
        }
    }
    let secs = t.elapsed().as_secs_f64();
    let mut f = std::io::BufWriter::new(std::fs::File::create(&args[2])?);
    writeln!(f, "position,k,i,delay_z,angle_z,label")?;
    for (p, k, labels) in &out {
        let x = &sets.iter().find(|s| s.0 == *p).expect("set").1;
        for (i, (v, l)) in x.iter().zip(labels).enumerate() {
            writeln!(f, "{p},{k},{i},{:.17e},{:.17e},{l}", v[0], v[1])?;
        }
    }
    println!(
        "fits={} points={} seconds={secs:.6}",
        out.len(),
        sets.iter().map(|s| s.1.len()).sum::<usize>() * 7
    );
    Ok(())
}
