"""sortbot: push, grasp and sort cutlery with a simulated UR3 and an RGB-D camera."""
__version__ = "0.1.0"
