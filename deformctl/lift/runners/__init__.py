"""Trial runners of the lifting-force search: an external rig (:mod:`.rig`), the simulator
(:mod:`.sim`)."""
