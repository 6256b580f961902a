"""Hand-built parameter sets of the four feeder shapes, for tests that ask a feeder (or what a
run records of it) what it has."""

# a 4 mm track, 1.2 mm wide, for 300 um spheres
TRACK = {"part_size": 3e-4, "shape": 0, "track_length": 4e-3, "track_width": 1.2e-3,
         "wall_height": 1e-3, "freq": 100, "amp_t": 3e-5, "amp_n": 5e-5, "phase": 0}
# and a 5 mm section 2, 60 um below it, with a side drop
LINE = {**TRACK, "sections": 2, "s2_length": 5e-3, "s2_width": 1.2e-3, "s2_wall_height": 6e-4,
        "s2_step": 6e-5, "s2_freq": 100, "s2_amp_t": 1.2e-4, "s2_amp_n": 2e-5, "s2_phase": 0,
        "s2_drop_from": 0.2, "s2_drop_to": 0.6, "s2_drop_width": 4e-4}
# a bowl 20 mm across, its track 1.2 mm wide climbing half a turn at 3 degrees to an 8 mm chute
BOWL = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 0.5,
        "wall_height": 1e-3, "chute_length": 8e-3, "part_size": 3e-4, "shape": 0,
        "freq": 75, "amp_t": 2e-4, "amp_n": 4e-5, "phase": -60}
# and a 10 mm exit section after its chute
BOWL_LINE = {**BOWL, "sections": 2, "s2_length": 0.01, "s2_width": 1.5e-3, "s2_wall_height": 1e-3,
             "s2_step": 5e-5, "s2_freq": 75, "s2_amp_t": 4e-4, "s2_amp_n": 4e-5, "s2_phase": -60}
