use viscobar::{closed_form, scene, study};
fn main() {
    for name in ["modal", "impact", "clamped-impact"] {
        let (_, base) = scene::load(name, &[]).unwrap();
        let exact = closed_form::for_scene(name, &base).unwrap();
        let mut hs = vec![];
        let mut es = vec![];
        for level in 0..5 {
            let f = 1u64 << level;
            let mut s = base.clone();
            s.mesh.elements = base.mesh.elements * f;
            s.time.step = base.time.step / f as f64;
            let e = study::error_against(&s, exact.as_ref()).unwrap();
            println!(
                "{name} J+1={} dt={} l2={:.3e} max={:.3e}",
                s.mesh.elements, s.time.step, e.l2, e.max
            );
            hs.push(s.dx());
            es.push(e.l2);
        }
        println!("{name} order {:.3}", study::observed_order(&hs, &es));
    }
}
