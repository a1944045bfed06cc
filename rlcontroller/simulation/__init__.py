"""The closed loop between control and learning: a plant stepped under a ground motion, its sensors
and their noise, the observation every controller reads, and many buildings stepped together
(`batch`). Evaluation, the safety check, validation and random search simulate here without the RL
package; the gymnasium env (`learning.env`) is built on the same pieces."""
