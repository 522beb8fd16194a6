"""The K2-or-asymmetry study: calibration runs with a true K2 or a true scale asymmetry made
with numpy (:mod:`.runs`), scored by the whole analysis (:mod:`.score`)."""
