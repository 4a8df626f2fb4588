use crate::error::SolveError;
/// Dimensionless response equation (stub).
#[derive(Debug, Clone, Copy)]
pub struct ResponseEquation { pub s0: f64, pub s1: f64, pub rho: f64, pub d0: f64, pub d1: f64, pub eta: f64 }
impl ResponseEquation {
    pub fn new(s0: f64, s1: f64, rho: f64, d0: f64, d1: f64, eta: f64) -> Self { Self { s0, s1, rho, d0, d1, eta } }
    pub fn roots(&self) -> Result<Vec<f64>, SolveError> { todo!() }
    pub fn phase(&self, _x: f64) -> f64 { todo!() }
    pub fn is_stable(&self, _x: f64) -> bool { todo!() }
}
