use radray::progress::Progress;
use radray::run::{self, RunStats};
use radray::transport::photons::RunPhotons;
fn main() {
    let mut s = radray::scene::load(std::path::Path::new("scenes/rooms/living_room.toml")).unwrap();
    s.radiosity.method = radray::scene::MethodChoice::Adaptive;
    let (mesh, sol) =
        run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut RunStats::default()).unwrap();
    let e = &mesh.elements;
    for i in 0..e.len() {
        let c = e.centre[i];
        if e.normal[i].y > 0.9 && (c.y - 0.55).abs() < 1e-3 && c.x > 0.74 && c.x < 1.26 && c.z > 3.34 && c.z < 3.86 {
            let moved = mesh.element_eye.get(i).is_some_and(|&p| p != c);
            let buried = mesh.element_buried.get(i).copied().unwrap_or(false);
            let d = ((c.x - 1.0).powi(2) + (c.z - 3.6).powi(2)).sqrt();
            println!(
                "{:4} c ({:.3},{:.3}) d {:.3} area {:.4} B {:.2} buried {} moved {} eye {:?}",
                i,
                c.x,
                c.z,
                d,
                e.area[i],
                sol.element_exitance[i].x,
                buried,
                moved,
                mesh.element_eye.get(i).map(|p| (p.x, p.z))
            );
        }
    }
    // vertex values on the table top
    for (v, p) in mesh.positions.iter().enumerate() {
        if (p.y - 0.55).abs() < 1e-3 && p.x > 0.74 && p.x < 1.26 && p.z > 3.34 && p.z < 3.86 {
            let val = sol.vertex_exitance[v].x;
            if val > 0.0 {
                println!("v ({:.3},{:.3}) B {:.2}", p.x, p.z, val);
            }
        }
    }
}
