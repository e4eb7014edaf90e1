//! The node's ROS parameters and its robot_description: what is declared, what a new value
//! must satisfy (checked in ros2-client's spinner, so `ros2 param set` reports why not), and
//! how an accepted value is applied on the event loop.
//!
//! A new robot_description (parameter or `--robot-description-topic`) replaces the mechanism
//! that came from one, and new load-time settings analyse every mechanism again.

use super::publish::topics;
use super::{mechanism_entry, panic_text, Event};
use crate::edges::ros::{convert, ServeConfig, Source};
use ros2_client::log::LogLevel;
use ros2_client::{NodeOptions, ParameterValue};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The node's ROS parameters: their initial values (from the command line, `-p` and
/// `--params-file`), checked by `check_parameter` when set through the parameter services.
fn declared_parameters(config: &ServeConfig) -> Vec<(&'static str, ParameterValue)> {
    let description = config.sources.iter().find(|s| s.description).map_or(String::new(), |s| s.xml.clone());
    let l = &config.limits;
    vec![
        ("robot_description", ParameterValue::String(description)),
        ("sigma", ParameterValue::Double(config.settings.sigma)),
        ("rho", ParameterValue::Double(config.settings.rho)),
        ("precision", ParameterValue::Double(config.precision)),
        ("max_request_boxes", ParameterValue::Integer(l.max_boxes.min(i64::MAX as u64) as i64)),
        ("max_request_timeout", ParameterValue::Double(l.max_timeout)),
        ("max_wait", ParameterValue::Double(l.max_wait)),
        ("max_runs", ParameterValue::Integer(l.max_runs as i64)),
        ("max_markers", ParameterValue::Integer(l.max_markers as i64)),
        ("max_set_megabytes", ParameterValue::Double(l.max_set_megabytes)),
    ]
}

/// Whether a parameter value is acceptable; the reason otherwise (one line, shown by
/// `ros2 param set`). A URDF must parse.
fn check_parameter(name: &str, value: &ParameterValue) -> Result<(), String> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    match (name, value) {
        ("robot_description", ParameterValue::String(xml)) if xml.trim().is_empty() => Ok(()),
        ("robot_description", ParameterValue::String(xml)) => crate::app::parse_urdf(xml).map(|_| ()).map_err(|e| format!("robot_description: {}", convert::bounded(&e.to_string(), convert::ECHO_MESSAGE))),
        ("sigma", ParameterValue::Double(v)) if positive(*v) => Ok(()),
        ("rho", ParameterValue::Double(v)) if *v > 0.0 && *v < 1.0 => Ok(()),
        ("precision", ParameterValue::Double(v)) if *v > 0.0 && *v < 1.0 => Ok(()),
        ("max_request_timeout" | "max_set_megabytes", ParameterValue::Double(v)) if positive(*v) => Ok(()),
        ("max_wait", ParameterValue::Double(v)) if v.is_finite() && *v >= 0.0 => Ok(()),
        ("max_request_boxes" | "max_runs" | "max_markers", ParameterValue::Integer(v)) if *v > 0 => Ok(()),
        ("robot_description", _) => Err("robot_description must be a string (URDF XML)".into()),
        ("sigma" | "max_request_timeout" | "max_set_megabytes", _) => Err(format!("{name} must be a positive finite double")),
        ("rho" | "precision", _) => Err(format!("{name} must be a double in (0, 1)")),
        ("max_wait", _) => Err("max_wait must be a finite double >= 0".into()),
        ("max_request_boxes" | "max_runs" | "max_markers", _) => Err(format!("{name} must be a positive integer")),
        _ => Err(format!("'{}' is not a parameter of this node", convert::bounded(name, convert::ECHO_NAME))),
    }
}

/// The node's options: rosout, the parameter services, the declared parameters, and the
/// validator and set action of parameter changes (a change reaches the loop as an `Event`).
pub(super) fn node_options(config: &ServeConfig, set_events: smol::channel::Sender<Event>) -> NodeOptions {
    let mut options = NodeOptions::new().enable_rosout(config.rosout).start_parameter_services(true);
    for (name, value) in declared_parameters(config) {
        options = options.declare_parameter(name, value);
    }
    // A robot_description is checked as the node will load it (URDF, formulation, the
    // load-time --fix and --trace that name its robot), so `ros2 param set` reports why not.
    let load_config = config.clone();
    let validate = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        check_parameter(name, value)?;
        match value {
            ParameterValue::String(xml) if name == "robot_description" && !xml.trim().is_empty() => {
                let source = Source { label: "robot_description".into(), xml: xml.clone(), description: true };
                let (mut fixes, mut traces) = (vec![false; load_config.fixed.len()], vec![false; load_config.traces.len()]);
                crate::edges::ros::load_one(&source, &load_config, &mut fixes, &mut traces).map(|_| ()).map_err(|e| convert::bounded(&format!("{e:#}"), convert::ECHO_MESSAGE))
            }
            _ => Ok(()),
        }
    };
    let validator = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        // It runs in ros2-client's spinner: a bug must refuse the value, not stop the spinner.
        catch_unwind(AssertUnwindSafe(|| validate(name, value))).unwrap_or_else(|p| Err(format!("internal error while checking {name}: {}", panic_text(p.as_ref()))))
    };
    options.parameter_validator(Box::new(validator)).parameter_set_action(Box::new(move |name: &str, value: &ParameterValue| {
        // Applied by the event loop; a full queue refuses the change rather than block DDS.
        set_events.try_send(Event::Parameter(name.to_string(), value.clone())).map_err(|_| "the node is busy; retry".to_string())
    }))
}

impl super::State {
    /// A new robot_description (parameter or topic): replaces the mechanism that came from
    /// one (or adds it), and analyses it again. Errors are one line, logged.
    pub(super) fn new_description(&mut self, xml: String, origin: &str) {
        if xml == self.description {
            return;
        }
        if xml.trim().is_empty() {
            self.description = xml;
            return;
        }
        let source = Source { label: origin.to_string(), xml: xml.clone(), description: true };
        let (mut fixes, mut traces) = (vec![false; self.config.fixed.len()], vec![false; self.config.traces.len()]);
        let loaded = match crate::edges::ros::load_one(&source, &self.config, &mut fixes, &mut traces) {
            Ok(l) => l,
            Err(e) => return self.log(LogLevel::Error, convert::bounded(&format!("{e:#}"), convert::ECHO_MESSAGE).to_string()),
        };
        let slot = self.mechanisms.iter().position(|m| m.loaded.description);
        let name = loaded.analysis.mechanism().to_string();
        if let Some(other) = self.mechanisms.iter().enumerate().find(|(k, m)| Some(*k) != slot && (m.loaded.analysis.mechanism() == name || m.loaded.token == loaded.token)) {
            return self.log(LogLevel::Error, format!("{origin}: a mechanism named '{}' is already loaded from another source", other.1.loaded.analysis.mechanism()));
        }
        self.description = xml.clone();
        if origin != "parameter robot_description" {
            // Keep the parameter in step with what the node analyses (its set action sees
            // the same text and does nothing).
            let _ = self.node.set_parameter("robot_description", ParameterValue::String(xml));
        }
        let prefix = format!("{}/{}", self.base, loaded.token);
        let k = match slot {
            Some(k) => {
                self.retire(k);
                if self.mechanisms[k].prefix != prefix {
                    match topics(&mut self.node, &prefix) {
                        Ok(t) => self.mechanisms[k].topics = t,
                        Err(e) => return self.log(LogLevel::Error, format!("{origin}: {e:#}")),
                    }
                    self.mechanisms[k].prefix = prefix;
                }
                self.mechanisms[k].loaded = loaded;
                k
            }
            None => {
                let t = match topics(&mut self.node, &prefix) {
                    Ok(t) => t,
                    Err(e) => return self.log(LogLevel::Error, format!("{origin}: {e:#}")),
                };
                let generation = self.next_generation;
                self.next_generation += 1;
                self.mechanisms.push(mechanism_entry(loaded, prefix, t, generation));
                self.mechanisms.len() - 1
            }
        };
        self.log(LogLevel::Info, format!("{name}: new robot_description from {origin}; analysing again"));
        self.start_load_time(k);
        self.publish_static_transforms();
    }
    /// A parameter set through the parameter services (validated by `check_parameter`).
    pub(super) fn parameter(&mut self, name: &str, value: ParameterValue) {
        let before = (self.settings.clone(), self.precision);
        match (name, value) {
            ("robot_description", ParameterValue::String(xml)) => return self.new_description(xml, "parameter robot_description"),
            ("sigma", ParameterValue::Double(v)) => self.settings.sigma = v,
            ("rho", ParameterValue::Double(v)) => self.settings.rho = v,
            ("precision", ParameterValue::Double(v)) => self.precision = v,
            ("max_request_boxes", ParameterValue::Integer(v)) => self.limits.max_boxes = v.max(1) as u64,
            ("max_request_timeout", ParameterValue::Double(v)) => self.limits.max_timeout = v,
            ("max_wait", ParameterValue::Double(v)) => self.limits.max_wait = v,
            ("max_runs", ParameterValue::Integer(v)) => self.limits.max_runs = v.max(1) as usize,
            ("max_markers", ParameterValue::Integer(v)) => self.limits.max_markers = v.max(1) as usize,
            ("max_set_megabytes", ParameterValue::Double(v)) => self.limits.max_set_megabytes = v,
            _ => return,
        }
        // New load-time settings: every mechanism is analysed again with them.
        if (self.settings.clone(), self.precision) != before {
            self.log(LogLevel::Info, format!("parameter {name} changed: analysing every mechanism again"));
            for k in 0..self.mechanisms.len() {
                self.retire(k);
                self.start_load_time(k);
            }
        }
    }
}
