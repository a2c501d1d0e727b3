"""A calibration made elsewhere read as the correction it applies, a = M (raw - b) in garant's terms: imu_tk's
CalibratedTriad text, imucal's FerrarisCalibrationInfo JSON, a PX4 .params or ArduPilot .parm file
(io/stack_params.py), or garant's own file; and garant's frame convention for it (workflows/budget.py judges it)."""
import numpy as np

from ..errors import DataError


def peer(path, flight=None, imu=None):
    """(kind, M, b, slot) of a calibration file: garant's own ("garant", the checked dictionary, None), imucal's
    FerrarisCalibrationInfo JSON (M = (K_a R_a)^-1, b = b_a: imucal's a = R_a^-1 K_a^-1 (raw - b_a)), a PX4 .params
    or ArduPilot .parm (io/stack_params.py: the slot of the log's accelerometer `flight`, or of `imu`) or imu_tk's
    CalibratedTriad text (M = T K, b = B); slot names a parameter file's calibration, None otherwise; DataError
    naming the file otherwise."""
    from ..io import calibration, files, stack_params
    files.regular(path, "the calibration file", calibration.MAX_BYTES, param="calibration")
    try:
        with open(path, "rb") as fh:
            start = fh.read(64).lstrip()
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="calibration") from None
    if start.startswith(b"{"):
        data = files.read_json(path, "a calibration file", calibration.MAX_BYTES, param="calibration")
        if isinstance(data, dict) and data.get("format") == calibration.FORMAT:
            return "garant", calibration.read(path), None, None
        if isinstance(data, dict) and all(k in data for k in ("K_a", "R_a", "b_a")):
            try:
                K, R, b = (np.array(data[k], dtype=float) for k in ("K_a", "R_a", "b_a"))
            except (TypeError, ValueError):
                K = None
            if K is None or K.shape != (3, 3) or R.shape != (3, 3) or b.shape != (3,) or not (
                    np.all(np.isfinite(K)) and np.all(np.isfinite(R)) and np.all(np.isfinite(b))):
                raise DataError(f"{path}: imucal's K_a and R_a must be 3 x 3 and b_a 3 finite numbers",
                                param="calibration")
            return "imucal", _regular(np.linalg.inv(K @ R) if abs(np.linalg.det(K @ R)) > 0 else None, path), b, None
        raise DataError(f"{path}: neither a garant calibration (format {calibration.FORMAT}) nor imucal's (K_a, R_a, "
                        "b_a)", param="calibration")
    params = stack_params.read(path)
    if params:
        stack, M, b, slot = stack_params.constant(params, path, flight, imu)
        return stack, _regular(M, path), b, slot
    M, b = calibration.read_imu_tk(path)
    return "imu_tk", _regular(M, path), b, None


def precheck(path, imu, flight_log):
    """`peer`'s refusals of the file, said before the log is calibrated; a parameter file's slot is left to the log
    when it is a flight log (its accelerometer chooses the slot)."""
    try:
        peer(path, None, imu)
    except DataError as e:
        if not (flight_log and e.param == "imu"):
            raise


def _regular(M, path):
    if M is None or not np.all(np.isfinite(M)) or np.linalg.cond(M) > 1e3:
        raise DataError(f"{path}: its matrix is singular or ill-conditioned: not a calibration of an accelerometer",
                        param="calibration")
    return M


def garant_frame(M):
    """(L, Q, turn_deg): M = Q L with L lower-triangular (positive diagonal), garant's convention, and Q the turn
    of the calibration's own frame from it (a norm relation sees |a| only: the turn is a convention, not an
    error). J A J = Q' R' (QR) gives A = (J Q' J)(J R' J), J R' J lower-triangular."""
    J = np.eye(3)[::-1]
    Qp, Rp = np.linalg.qr(J @ M @ J)
    Q, L = J @ Qp @ J, J @ Rp @ J
    S = np.diag(np.sign(np.diag(L)))
    Q, L = Q @ S, S @ L
    return np.tril(L), Q, float(np.degrees(np.arccos(np.clip((np.trace(Q) - 1) / 2, -1, 1))))
