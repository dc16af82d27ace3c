/* motorlab JVM test: a brushed DC motor + load, a bench supply behind a relay, a hub H-bridge and a clock. */
package org.firstinspires.ftc.teamcode.motorlab.sim;

/**
 * The truth of the JVM round trip. All quantities at the counted shaft (cpr counts per revolution):
 * J·dω/dt = K·i − b·ω − Tf·sgn(ω) with stiction (at rest while |K·i| ≤ Tf), and i from the source with
 * the inductance neglected (L/R ≈ 0.3 ms, far below the hub's sample interval):
 * <ul>
 * <li>relay closed, bench supply (Vs, current limit Ilim): i = min((Vs − K·ω)/R, Ilim), never negative
 *     (a bench supply does not sink current); terminal voltage R·i + K·ω;</li>
 * <li>relay open, or hub at power 0 with FLOAT: i = 0, terminal voltage K·ω (back-EMF);</li>
 * <li>hub: V = power·V_battery (average of the PWM), i = (V − K·ω)/R; BRAKE at power 0 shorts the motor.</li>
 * </ul>
 * V_battery = V0 − R_battery·|i| while the hub drives.
 */
public final class Plant {
    public double K = 0.75, R = 2.5, J = 0.1, b = 0.02, Tf = 0.05, cpr = 1120;
    public double supplyVolts = 12.0, supplyAmps = 2.5;
    public double batteryVolts = 13.0, batteryOhms = 0.05;
    public boolean relayClosed = false;
    public double hubPower = 0.0;
    public boolean brake = false;

    /** Keep the simulated time no further ahead of the wall clock than 1 ms (a robot for the emulator). */
    public boolean realtime = false;
    private long nanos = 0;
    private long wallZero = -1;
    private double theta = 0.0, omega = 0.0, current = 0.0, terminal = 0.0;
    /** Angle on a 1 ms grid for the hub's velocity (counts over the last 50 ms, × 20). */
    private final double[] history = new double[64];
    private long historyMillis = 0;

    private static final double DT = 1e-4;

    public long nanos() {
        return nanos;
    }

    public double seconds() {
        return nanos * 1e-9;
    }

    /** Let the world run for {@code seconds}. */
    public void advance(double seconds) {
        long end = nanos + Math.round(seconds * 1e9);
        while (nanos < end) {
            long stepNanos = Math.min(Math.round(DT * 1e9), end - nanos);
            step(stepNanos * 1e-9);
            nanos += stepNanos;
            long millis = nanos / 1000000L;
            while (historyMillis < millis) {
                historyMillis++;
                history[(int) (historyMillis % history.length)] = theta;
            }
        }
        if (realtime) {
            pace();
        }
    }

    private void pace() {
        if (wallZero < 0) {
            wallZero = System.nanoTime() - nanos;
        }
        long ahead = nanos - (System.nanoTime() - wallZero);
        if (ahead > 1000000L) {
            try {
                Thread.sleep(ahead / 1000000L, (int) (ahead % 1000000L));
            } catch (InterruptedException e) {
                Thread.currentThread().interrupt();
            }
        }
    }

    private void electrical() {
        double emf = K * omega;
        if (relayClosed) {
            double i = Math.min((supplyVolts - emf) / R, supplyAmps);
            current = Math.max(i, 0.0);
            terminal = current > 0 ? R * current + emf : emf;
        } else if (hubPower != 0.0 || brake) {
            double v = hubPower * battery();
            current = (v - emf) / R;
            terminal = v;
        } else {
            current = 0.0;
            terminal = emf;
        }
    }

    private void step(double dt) {
        electrical();
        double drive = K * current - b * omega;
        if (omega == 0.0 && Math.abs(drive) <= Tf) {
            return; // stiction holds the shaft
        }
        double sign = omega != 0.0 ? Math.signum(omega) : Math.signum(drive);
        double next = omega + dt * (drive - Tf * sign) / J;
        if (omega != 0.0 && Math.signum(next) != Math.signum(omega) && Math.abs(K * current) <= Tf) {
            next = 0.0; // friction stops the shaft, it does not reverse it
        }
        theta += 0.5 * (omega + next) * dt;
        omega = next;
    }

    public double battery() {
        return batteryVolts - batteryOhms * Math.abs(current);
    }

    /** Quadrature counts of the encoder (floor of the angle in counts). */
    public int counts() {
        return (int) Math.floor(theta * cpr / (2 * Math.PI));
    }

    /** The hub's velocity: counts moved in the last 50 ms, × 20 [counts/s]. */
    public double hubVelocity() {
        long now = historyMillis;
        if (now < 50) {
            return 0.0;
        }
        double then = history[(int) ((now - 50) % history.length)];
        double c0 = Math.floor(then * cpr / (2 * Math.PI));
        double c1 = Math.floor(history[(int) (now % history.length)] * cpr / (2 * Math.PI));
        return 20.0 * (c1 - c0);
    }

    public double current() {
        electrical();
        return current;
    }

    /** Voltage at the motor's + terminal against ground (what the INA219's bus input sees). */
    public double terminalVolts() {
        electrical();
        return terminal;
    }

    public double omega() {
        return omega;
    }
}
