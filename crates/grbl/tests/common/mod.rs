//! Shared helpers for the end-to-end tests.
#![allow(dead_code)]

use std::time::Duration;

use cell_grbl::program::{CleanOptions, Program};
use cell_grbl::sim::{self, SimConfig, SimHandle};
use cell_grbl::stream::{ClientConfig, FlowControl, GrblClient};

/// A program the emitter could have written: header comment, modal setup, heat on, a dwell,
/// `n` short feed moves with the odd arc and comment, heat off, end.
pub fn program_text(n: usize) -> String {
    let mut s =
        String::from("(cellsuite test program)\nG17 G21 G90 G94\nG0 X0 Y0\nM3 S300\nG4 P0.05\n");
    for i in 0..n {
        let x = (i % 50) as f64 * 0.2;
        let y = (i / 50) as f64 * 0.2;
        if i % 25 == 7 {
            // Half circle from the previous point (x - 0.2, y) about (x - 0.1, y).
            s += &format!("G2 X{x:.3} Y{y:.3} I0.100 J0 F900 ; arc\n");
        } else if i % 40 == 3 {
            s += "\n(comment line)\n";
            s += &format!("G1 X{x:.3} Y{y:.3}\n");
        } else {
            s += &format!("G1 X{x:.3} Y{y:.3} F1200\n");
        }
    }
    s += "M5\nG0 X0 Y0\nM2\n";
    s
}

/// How long (tokio time) a test waits on the simulator before failing instead of hanging.
pub const WAIT: Duration = Duration::from_secs(120);

pub fn program(n: usize) -> Program {
    Program::parse(&program_text(n), CleanOptions::default()).expect("test program is valid")
}

pub fn texts(p: &Program) -> Vec<String> {
    p.lines().iter().map(|l| l.text.clone()).collect()
}

pub fn client_config(flow: FlowControl) -> ClientConfig {
    ClientConfig {
        flow,
        ..ClientConfig::default()
    }
}

/// A simulator and a client connected in-process (use with a paused tokio clock).
pub async fn in_process(sim_cfg: SimConfig, flow: FlowControl) -> (SimHandle, GrblClient) {
    let sim = sim::start(sim_cfg);
    let client = GrblClient::connect(sim.connector(), client_config(flow))
        .await
        .expect("connect to the simulator");
    (sim, client)
}
