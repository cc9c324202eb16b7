"""The robot's physics that more than the simulator needs: contact materials and their
friction (``materials``), the SMA coil's and body's thermal constants (``thermal``), and the
physical plant's parameters from the robot file (``params``). Below the firmware in the
package layering: a build takes the coil's thermal time constant from here
(``[safety] coil_heat_ceiling``) without importing the simulator."""
