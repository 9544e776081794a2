"""System identification on the rig: excitation signals, frequency-response estimates, Bode plots.

- :mod:`harness.identification.excitation`: the excitation (a logarithmic chirp or
  band-limited random force), its check against the profile's force limits, and the
  controller that plays it through the loop's supervisor like any controller's force;
- :mod:`harness.identification.frf`: the H1 frequency-response estimate (Welch averaging)
  with its coherence, and its CSV file;
- :mod:`harness.identification.plot`: the Bode plot (magnitude, phase, coherence).

``harness identify actuator`` (:mod:`harness.runs.identify`) puts them together.
"""
