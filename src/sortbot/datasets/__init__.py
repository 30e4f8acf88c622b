"""Dataset formats: the LeRobot v3 dataset and MCAP logs sortbot writes and reads (the only code that knows file formats)."""
