use gleaner_op_formats::load_instance;
use gleaner_orienteering::{SolveOptions, solve_default};
fn main() {
    let p = std::env::args().nth(1).unwrap();
    let inst = load_instance(std::path::Path::new(&p)).unwrap();
    let d = solve_default(
        &inst.problem,
        &SolveOptions::default().with_time_limit(std::time::Duration::from_secs(3)),
    );
    let r: Vec<String> = d.routes[0].iter().map(|v| (v + 1).to_string()).collect();
    println!("{}", r.join(" "));
}
