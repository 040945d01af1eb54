//! The pixel art, as text: one character per cell, `.` transparent, other characters looked up in [`PALETTE`].
//!
//! Each sprite is drawn at exactly its `SPEC.md` size. The chopper is drawn in 2 × 2-pixel cells (32 × 32 cells
//! make its 64 × 64 pixels); the others in single pixels. All of it is ours, made for this game.

/// A sprite's pixel art.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Art {
    /// One string per row of cells, all of the same length.
    pub rows: &'static [&'static str],
    /// Pixels per cell side.
    pub cell: usize,
}

impl Art {
    /// Width in native pixels.
    pub fn width(&self) -> usize {
        self.rows[0].len() * self.cell
    }

    /// Height in native pixels.
    pub fn height(&self) -> usize {
        self.rows.len() * self.cell
    }

    /// The colour of native pixel `(x, y)`, `None` where transparent.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[u8; 3]> {
        color(self.rows[y / self.cell].as_bytes()[x / self.cell])
    }
}

/// The colours of the art, by character.
pub(crate) const PALETTE: [(u8, [u8; 3]); 17] = [
    (b'k', [24, 24, 32]),    // outline, near black
    (b'g', [96, 100, 110]),  // rotor grey
    (b'G', [160, 165, 175]), // light grey (rotor blur, missile body)
    (b'b', [38, 110, 215]),  // chopper blue
    (b'B', [22, 62, 140]),   // chopper dark blue (shade)
    (b'c', [170, 230, 255]), // cockpit glass
    (b'o', [205, 110, 45]),  // bird body, orange-brown
    (b'O', [140, 70, 30]),   // bird wing, dark brown
    (b'y', [250, 200, 20]),  // beak, label, flame yellow
    (b'w', [255, 255, 250]), // eye white
    (b'r', [215, 35, 35]),   // fuel tank red, missile nose
    (b'R', [140, 20, 20]),   // dark red
    (b'a', [70, 200, 70]),   // alien green
    (b'A', [30, 120, 40]),   // alien dark green
    (b'p', [150, 60, 210]),  // alien purple wings
    (b'P', [95, 30, 140]),   // alien dark purple
    (b'f', [255, 130, 0]),   // flame orange
];

/// The colour of a cell character; `None` for `.` (transparent).
pub(crate) fn color(ch: u8) -> Option<[u8; 3]> {
    PALETTE.iter().find(|(c, _)| *c == ch).map(|&(_, rgb)| rgb)
}

/// The chopper, 64 × 64 pixels (32 × 32 cells of 2 × 2), facing right: main rotor on a mast, cabin with
/// cockpit glass at the front, tail boom with a fin and tail rotor at the back, two skids.
pub(crate) const CHOPPER: Art = Art {
    cell: 2,
    rows: &[
        "................................",
        "................................",
        "................................",
        "................................",
        "GGGggggggggggggggggggggggggggGGG",
        "..............kkkk..............",
        "...............kk...............",
        "...............kk...............",
        "...........kkkkkkkkkk...........",
        ".........kkbbbbbbbbbbkk.........",
        ".g......kbbbbbbbbbbbbcckk.......",
        ".gk....kbbbbbbbbbbbbbccccck.....",
        ".gbk..kbbbbbbbbbbbbbbcccccck....",
        "ggggggkbbbbbbbbbbbbbbccccccck...",
        ".gbbkkkbbbbbbbbbbbbbbcccccccck..",
        ".gbbbbbbbbbbbbbbbbbbbbbbbbbbbbk.",
        ".kBBBBBBBBBBBbbbbbbbbbbbbbbbbbbk",
        "..kkkkkkkkkkkBBBBBBBBBBBBBBBBBBk",
        "............kBBBBBBBBBBBBBBBBBk.",
        ".............kBBBBBBBBBBBBBBBk..",
        "..............kkkkkkkkkkkkkkk...",
        "...............k.........k......",
        "...............k.........k......",
        "...............k.........k......",
        "..........kkkkkkkkkkkkkkkkkkkkk.",
        "...........kkkkkkkkkkkkkkkkkkk..",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
    ],
};

/// A bird, 32 × 32, flying left: brown body, a raised dark wing, yellow beak, white eye.
pub(crate) const BIRD: Art = Art {
    cell: 1,
    rows: &[
        "................................",
        "................................",
        "................................",
        "................................",
        "................OO..............",
        "...............OOOO.............",
        "..............OOOOOO............",
        ".............OOOOOOOO...........",
        "............OOOOOOOOO...........",
        "...........OOOOOOOOOO...........",
        "......ooo.OOOOOOOOOO............",
        ".....ooooooOOOOOOOOO............",
        "....oowwkooOOOOOOOO.............",
        "...oooowkoooOOOOOOooo......ooo..",
        "yyyooooooooooooooooooooo..oooo..",
        ".yyyyoooooooooooooooooooooooo...",
        "...yyoooooooooooooooooooooooo...",
        "......oooooooooooooooooooooooo..",
        ".......ooooooooooooooooooo..ooo.",
        ".........ooooooooooooooo.....oo.",
        "...........ooooooooooo..........",
        ".............k....k.............",
        "............kk...kk.............",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
    ],
};

/// A fuel tank, 32 × 32: a red jerry can with a handle, a spout and a yellow fuel-drop label.
pub(crate) const FUEL_TANK: Art = Art {
    cell: 1,
    rows: &[
        "................................",
        "..........kkkkkkkk....kkkk......",
        ".........kRRRRRRRRk..kGGGGk.....",
        ".........kRkkkkkkRk..kGGGGk.....",
        ".........kRk....kRk.kkkkkkkk....",
        "......kkkkRkkkkkkRkkkRRRRRRk....",
        ".....krrrrrrrrrrrrrrrrrrrrrrk...",
        "....krrrrrrrrrrrrrrrrrrrrrrrrk..",
        "....krrRRRRRRRRRRRRRRRRRRRRrrk..",
        "....krrRrrrrrrrrrrrrrrrrrrRrrk..",
        "....krrRrrrrrrrryrrrrrrrrrRrrk..",
        "....krrRrrrrrrryyyrrrrrrrrRrrk..",
        "....krrRrrrrrryyyyyrrrrrrrRrrk..",
        "....krrRrrrrrryyyyyrrrrrrrRrrk..",
        "....krrRrrrrryyyyyyyrrrrrrRrrk..",
        "....krrRrrrryyyyyyyyyrrrrrRrrk..",
        "....krrRrrrryyyyyyyyyrrrrrRrrk..",
        "....krrRrrrryyyyyyyyyrrrrrRrrk..",
        "....krrRrrrrryyyyyyyrrrrrrRrrk..",
        "....krrRrrrrrryyyyyrrrrrrrRrrk..",
        "....krrRrrrrrrrrrrrrrrrrrrRrrk..",
        "....krrRrrrrrrrrrrrrrrrrrrRrrk..",
        "....krrRRRRRRRRRRRRRRRRRRRRrrk..",
        "....krrrrrrrrrrrrrrrrrrrrrrrrk..",
        "....krrrrrrrrrrrrrrrrrrrrrrrrk..",
        "....kRRRRRRRRRRRRRRRRRRRRRRRRk..",
        ".....kkkkkkkkkkkkkkkkkkkkkkkk...",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
    ],
};

/// An alien bird, 32 × 32, flying left: green body, purple bat wings, two big eyes with red pupils,
/// antennae. Unlike a bird in colour and shape.
pub(crate) const ALIEN: Art = Art {
    cell: 1,
    rows: &[
        "................................",
        ".......k.....k..................",
        "........k...k...................",
        ".........k.k....................",
        "........aaaaa...................",
        "......aaaaaaaaa.......P.........",
        ".....aawwwaawwwa.....PP.....P...",
        ".....awwrwaawrwwa...PPP....PP...",
        "....aawrrwaawrrwa..PPpP...PPP...",
        "....aawwwwaawwwwa.PPppPP.PPpP...",
        "....aaawwaaaawwaaPPpppPPPPppP...",
        "....aaaaaaaaaaaaaPpppppPPpppP...",
        "...yaaaaaaaaaaaaaaPpppppppppP...",
        "..yyAaaaaaaaaaaaaaaPppppppppP...",
        "...yaAAAAaaaaaaaaaaaPpppppppP...",
        "....aaaaaaaaaaaaaaaaaPPpppppPP..",
        ".....aaaaaaaaaaaaaaaaaaPPPpppP..",
        "......aAaAaAaAaaaaaaaaaaaaPPPP..",
        ".......aaaaaaaaaaaaaaaaaaaa.....",
        "........aaaaaaaaaaaaaaaaaaaa....",
        ".........aaaaaaaaaaaaaa...aaa...",
        "...........AAAAAAAAAA.......aa..",
        "............k..k..k.............",
        "...........kk.kk.kk.............",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
        "................................",
    ],
};

/// A missile, 16 × 8, flying left: red nose, grey body with fins, a flame at the back.
pub(crate) const MISSILE: Art = Art {
    cell: 1,
    rows: &[
        "...........kk...",
        "..kkkkkkkkkRk...",
        ".krrGGGGGGGGGkyf",
        "krrrGGGGGGGGGkff",
        "krrrGGGGGGGGGkff",
        ".krrGGGGGGGGGkyf",
        "..kkkkkkkkkRk...",
        "...........kk...",
    ],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sprite_has_its_spec_size_and_known_colours() {
        use crate::consts::*;
        for (art, (w, h)) in [
            (CHOPPER, CHOPPER_SIZE),
            (BIRD, BIRD_SIZE),
            (FUEL_TANK, FUEL_TANK_SIZE),
            (ALIEN, ALIEN_SIZE),
            (MISSILE, MISSILE_SIZE),
        ] {
            assert_eq!((art.width(), art.height()), (w as usize, h as usize));
            for row in art.rows {
                assert_eq!(row.len() * art.cell, w as usize, "row {row:?}");
                assert!(row.bytes().all(|c| c == b'.' || color(c).is_some()), "row {row:?}");
            }
        }
    }
}
