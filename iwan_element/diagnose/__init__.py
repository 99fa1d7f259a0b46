"""Model-discrepancy diagnosis: which physical effect the Iwan model misses."""
from .diagnosis import (CANDIDATES, Diagnosis, VibrationDiagnosis, diagnose, diagnose_vibration,
                        simulate_element_test)

__all__ = ["CANDIDATES", "Diagnosis", "VibrationDiagnosis", "diagnose", "diagnose_vibration",
           "simulate_element_test"]
