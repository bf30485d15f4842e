"""cablecheck simulation side: MuJoCo models, scenes, motion, the run loop, recording and the command line."""
