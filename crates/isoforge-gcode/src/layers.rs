//! Where each layer of a print starts.
//!
//! From the slicer's `;LAYER:n` comments when it wrote them (Cura, isoforge); otherwise a
//! layer starts with the Z move before the first extrusion at a new height, so that z-hops
//! (Z moves without extrusion) do not count as layers.

use crate::command::Command;
use crate::machine::Effect;

/// Where a layer starts in a list of commands.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// The layer's number (from `;LAYER:n`, else counted from 0).
    pub number: u32,
    /// Index of the layer's first command.
    pub first_command: usize,
    /// The layer's height, when a Z move for it was seen.
    pub z: Option<f64>,
}

/// Finds layer starts while commands go by.
#[derive(Debug, Default)]
pub struct LayerFinder {
    from_comments: Vec<Layer>,
    from_z: Vec<Layer>,
    z: Option<f64>,
    z_move_at: usize,
    layer_z: Option<f64>,
}

impl LayerFinder {
    /// A comment seen before command `next_command`.
    pub fn comment(&mut self, comment: &str, next_command: usize) {
        if let Some(number) = comment
            .strip_prefix("LAYER:")
            .and_then(|n| n.trim().parse().ok())
        {
            self.from_comments.push(Layer {
                number,
                first_command: next_command,
                z: None,
            });
        }
    }

    /// Command `index`, `cmd`, had `effect`.
    pub fn command(&mut self, cmd: &Command, effect: &Effect, index: usize) {
        let Effect::Move(mv) = effect else {
            return;
        };
        if cmd.get('Z').is_some() {
            self.z = mv.to[2];
            self.z_move_at = index;
            // A comment-marked layer gets its height from its first Z move.
            if let Some(last) = self.from_comments.last_mut()
                && last.z.is_none()
                && last.first_command <= index
            {
                last.z = self.z;
            }
        }
        if mv.e > 0.0 && self.z.is_some() && self.z != self.layer_z {
            self.layer_z = self.z;
            self.from_z.push(Layer {
                number: self.from_z.len() as u32,
                first_command: self.z_move_at.min(index),
                z: self.z,
            });
        }
    }

    /// The layers found: the commented ones if the file had any, else those found by height.
    pub fn finish(self) -> Vec<Layer> {
        if self.from_comments.is_empty() {
            self.from_z
        } else {
            self.from_comments
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Machine, lines, parse_line};

    fn layers(text: &str) -> Vec<Layer> {
        let mut m = Machine::default();
        let mut f = LayerFinder::default();
        let mut index = 0;
        for (_, raw) in lines(text) {
            let line = parse_line(raw).unwrap();
            if let Some(c) = line.comment {
                f.comment(c, index);
            }
            if let Some(cmd) = &line.command {
                let effect = m.apply(cmd);
                f.command(cmd, &effect, index);
                index += 1;
            }
        }
        f.finish()
    }

    #[test]
    fn layers_from_comments_take_their_height_from_the_first_z_move() {
        let l = layers(";LAYER:0\nG1 Z0.2\nG1 X1 E1\n;LAYER:1\nG1 Z0.4\nG1 X2 E2\n");
        assert_eq!(l.len(), 2);
        assert_eq!((l[1].number, l[1].first_command, l[1].z), (1, 2, Some(0.4)));
    }

    #[test]
    fn layers_from_height_ignore_z_hops() {
        let l = layers(
            "G90\nM82\nG1 Z0.2\nG1 X1 E1\nG1 Z0.6\nG1 X5\nG1 Z0.2\nG1 X6 E2\nG1 Z0.4\nG1 X7 E3\n",
        );
        let got: Vec<_> = l.iter().map(|l| (l.z, l.first_command)).collect();
        assert_eq!(got, [(Some(0.2), 2), (Some(0.4), 8)]);
    }
}
