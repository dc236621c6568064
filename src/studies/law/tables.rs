//! `law.csv` and `law.json` as text.

use std::fmt::Write as _;

use serde::Serialize;

use super::{FrictionLaw, T_FIELD, V_FIELD, fit_coordinates};
use crate::output::csv::push_f64;

/// Columns of `law.csv`.
pub const LAW_COLUMNS: &str = "plate.v,junctions.temperature,slip_rate_m_s,temperature_k,replicas,friction_per_junction,friction_per_junction_ci95,friction_n,friction_n_ci95,mu,mu_ci95,regime,stick_slip_fraction,steady";

/// Appends `,x`, or `,` alone when `x` is absent or not finite.
fn cell(s: &mut String, x: Option<f64>) {
    s.push(',');
    if let Some(x) = x.filter(|x| x.is_finite()) {
        push_f64(s, x);
    }
}

/// What the tables say about a point in stick-slip (also in the exports' comments).
pub const LEFT_OUT: &str = "a point that is not steady (any replica in stick-slip or unstable) has no steady friction coefficient: its mu is left empty in law.csv and it is left out of abaqus.inp and ansys.mac, so that a continuum code interpolates across it from the steady points around it (or holds the nearest one beyond them); its friction columns are time averages over the oscillation, not a steady friction";

impl FrictionLaw {
    /// `law.csv`: one row per point, `T` then `V` ascending.
    pub fn law_csv(&self) -> String {
        let mut s = format!("{LAW_COLUMNS}\n");
        for p in &self.points {
            push_f64(&mut s, p.v);
            s.push(',');
            push_f64(&mut s, p.t);
            cell(&mut s, Some(p.slip_rate));
            cell(&mut s, Some(p.kelvin));
            let _ = write!(s, ",{}", p.replicas);
            for e in [Some(p.friction_per_junction), Some(p.friction_newtons), p.mu] {
                cell(&mut s, e.map(|e| e.mean));
                cell(&mut s, e.map(|e| e.ci95));
            }
            let _ = write!(s, ",{}", p.regime.as_str());
            cell(&mut s, Some(p.stick_slip_fraction));
            let _ = writeln!(s, ",{}", p.steady);
        }
        s
    }

    /// `law.json`: the scales, the points left out, and the fitted form with its
    /// parameters, standard errors, residuals and goodness of fit.
    pub fn law_json(&self) -> String {
        #[derive(Serialize)]
        struct Units {
            l0_m: f64,
            t0_s: f64,
            t_ref_k: f64,
            normal_load_n: f64,
            force_unit_n: f64,
            force_unit: &'static str,
            velocity_unit_m_s: f64,
        }
        #[derive(Serialize)]
        struct Omitted {
            v: f64,
            temperature: f64,
            slip_rate_m_s: f64,
            temperature_k: f64,
            regime: &'static str,
            stick_slip_fraction: f64,
        }
        #[derive(Serialize)]
        struct Parameter {
            term: String,
            coefficient: f64,
            standard_error: Option<f64>,
        }
        #[derive(Serialize)]
        struct Residual {
            v: f64,
            temperature: f64,
            slip_rate_m_s: f64,
            temperature_k: f64,
            mu: f64,
            mu_fit: f64,
            residual: f64,
            sigma: Option<f64>,
        }
        #[derive(Serialize)]
        struct FitRecord {
            form: String,
            x: String,
            y: String,
            degree_requested: u32,
            degree: u32,
            parameters: Vec<Parameter>,
            weighted: bool,
            points: usize,
            dof: usize,
            chi_square: Option<f64>,
            reduced_chi_square: Option<f64>,
            p_value: Option<f64>,
            rms_residual: f64,
            residuals: Vec<Residual>,
        }
        #[derive(Serialize)]
        struct Record<'a> {
            scene: &'a str,
            fields: [&'static str; 2],
            replicas: usize,
            interval: &'static str,
            regime: &'static str,
            units: Units,
            points: usize,
            steady_points: usize,
            left_out_rule: &'static str,
            left_out: Vec<Omitted>,
            fit: Option<FitRecord>,
            #[serde(skip_serializing_if = "Option::is_none")]
            fit_error: Option<String>,
        }
        let sc = &self.scales;
        let fit = self.fit.as_ref().ok().map(|f| {
            let form = f
                .terms
                .iter()
                .enumerate()
                .map(
                    |(k, t)| if t.i + t.j == 0 && !t.linear_v { format!("c{k}") } else { format!("c{k}*{}", t.name()) },
                )
                .collect::<Vec<_>>()
                .join(" + ");
            FitRecord {
                form: format!("mu = {form}"),
                x: format!("ln(V / V0), V in m/s, V0 = l0 / t0 = {} m/s", sc.velocity_unit()),
                y: format!("T_ref / T - 1, T in K, T_ref = {} K", sc.t_ref),
                degree_requested: f.degree_requested,
                degree: f.degree,
                parameters: f
                    .terms
                    .iter()
                    .zip(&f.coefficients)
                    .zip(&f.standard_errors)
                    .map(|((t, c), e)| Parameter { term: t.name(), coefficient: *c, standard_error: *e })
                    .collect(),
                weighted: f.weighted,
                points: self.fitted.len(),
                dof: f.dof,
                chi_square: f.chi_square,
                reduced_chi_square: f.chi_square.filter(|_| f.dof > 0).map(|c| c / f.dof as f64),
                p_value: f.p_value,
                rms_residual: f.rms_residual,
                residuals: self
                    .fitted
                    .iter()
                    .zip(&f.residuals)
                    .map(|(&k, r)| {
                        let p = &self.points[k];
                        let mu = p.mu.expect("fitted points are steady");
                        let (x, y) = fit_coordinates(p.v, p.t);
                        Residual {
                            v: p.v,
                            temperature: p.t,
                            slip_rate_m_s: p.slip_rate,
                            temperature_k: p.kelvin,
                            mu: mu.mean,
                            mu_fit: f.eval(x, y),
                            residual: *r,
                            sigma: Some(mu.se).filter(|s| s.is_finite()),
                        }
                    })
                    .collect(),
            }
        });
        let r = Record {
            scene: &self.scene,
            fields: [V_FIELD, T_FIELD],
            replicas: self.replicas,
            interval: "95 % Student-t across replicas, t_{0.975, R-1} s / sqrt(R); none with one replica (then the fit is unweighted and its standard errors are scaled by the residual variance)",
            regime: "regime: the majority of the replicas (unstable if any replica is, mixed at a tie); steady: every replica smooth",
            units: Units {
                l0_m: sc.l0,
                t0_s: sc.t0,
                t_ref_k: sc.t_ref,
                normal_load_n: sc.normal_load,
                force_unit_n: sc.force_unit,
                force_unit: if sc.force_unit_derived { "kB T_ref / l0" } else { "given (--force-unit)" },
                velocity_unit_m_s: sc.velocity_unit(),
            },
            points: self.points.len(),
            steady_points: self.fitted.len(),
            left_out_rule: LEFT_OUT,
            left_out: self
                .points
                .iter()
                .filter(|p| !p.steady)
                .map(|p| Omitted {
                    v: p.v,
                    temperature: p.t,
                    slip_rate_m_s: p.slip_rate,
                    temperature_k: p.kelvin,
                    regime: p.regime.as_str(),
                    stick_slip_fraction: p.stick_slip_fraction,
                })
                .collect(),
            fit,
            fit_error: self.fit.as_ref().err().map(|e| e.to_string()),
        };
        serde_json::to_string_pretty(&r).expect("the record serializes") + "\n"
    }
}
