//! `lt list`: the registered integrators (`lt_integrators::INTEGRATORS`).

pub fn run() -> Result<(), String> {
    for i in lt_integrators::INTEGRATORS {
        println!("{:10} {}", i.name, i.about);
    }
    Ok(())
}
