/* motorlab: each loop's measurements to FTC Dashboard. Delete this file if your project has no FTC Dashboard. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.acmerobotics.dashboard.FtcDashboard;
import com.acmerobotics.dashboard.telemetry.TelemetryPacket;

/**
 * Sends every sample as one {@link TelemetryPacket} of numbers, keys named with their units (the table in
 * ftc/README.md), so that {@code motorlab robot record} logs them and {@code motorlab analyze} reads the log
 * without being told what a column is. {@link DynoOpMode} finds this class by name: without it (a project
 * without FTC Dashboard) the OpModes run the same and publish nothing. Only finite values are sent (a packet
 * value is text, and "NaN" is no number).
 */
public final class DashboardTelemetry implements DynoOpMode.Publisher {
    private final FtcDashboard dashboard = FtcDashboard.getInstance();

    @Override
    public boolean isActive() {
        return dashboard != null;
    }

    @Override
    public void publish(Sample s, boolean power, double batteryVolts, double countsPerRevolution) {
        if (dashboard == null) {
            return; // Dashboard not started on this robot
        }
        double radPerCount = 2 * Math.PI / countsPerRevolution;
        TelemetryPacket packet = new TelemetryPacket();
        put(packet, "time_s", s.time);
        packet.put("position_counts", s.counts);
        put(packet, "position_rad", s.counts * radPerCount);
        put(packet, "velocity_rad_per_s", s.velocity * radPerCount);
        if (power) {
            put(packet, "voltage_V", s.voltage);
            put(packet, "current_A", s.current);
        }
        put(packet, "battery_V", batteryVolts);
        dashboard.sendTelemetryPacket(packet);
    }

    private static void put(TelemetryPacket packet, String key, double value) {
        if (!Double.isNaN(value) && !Double.isInfinite(value)) {
            packet.put(key, value);
        }
    }
}
