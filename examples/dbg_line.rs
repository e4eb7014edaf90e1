use linkspace::interval::{interval, IntervalBox};
use linkspace::problems::coordinates::Placed;
use linkspace::problems::distance_file;
use linkspace::search::{Collect, SolverSettings};
use std::sync::atomic::AtomicBool;
fn main() {
    let d = distance_file::parse(&std::fs::read_to_string("urdf/four_spheres.json").unwrap(), &[]).unwrap();
    let pl = Placed::build_line(&d).unwrap();
    let r: Vec<Vec<f64>> = serde_json::from_str(&std::env::args().nth(1).unwrap()).unwrap();
    let b = IntervalBox::new(r.iter().map(|v| interval(v[0], v[1])).collect());
    for sigma in [0.0125, 0.003, 0.001] {
        let s = pl.solver(SolverSettings { sigma, rho: 0.9, max_boxes: 4000, ..Default::default() }).unwrap();
        let mut c = Collect::default();
        let (st, stats) = s.run_from(b.clone(), &AtomicBool::new(false), &mut c);
        println!("sigma {sigma} {st:?} processed {} found {} unique {:?}", stats.processed, c.solutions.len(), c.unique);
        for (x, u) in c.solutions.iter().zip(&c.unique) { if !u { println!("  {:?}", x.dims.iter().map(|i| (i.inf(), i.sup())).collect::<Vec<_>>()); } }
    }
}
