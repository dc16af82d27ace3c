// motorlab stub of FTC Dashboard's API (acmerobotics/ftc-dashboard; written from its public signatures, no
// Dashboard code): FtcDashboard/src/main/java/com/acmerobotics/dashboard/FtcDashboard.java at v0.4.16 (lines
// 166, 981) and v0.5.0 (lines 185, 1225); the same two signatures in every release from v0.4.10 to v0.6.0.
// Compile-time only: on a robot the real class is used. See ftc/README.md.
package com.acmerobotics.dashboard;

import com.acmerobotics.dashboard.telemetry.TelemetryPacket;

/**
 * Stub of FtcDashboard: only what motorlab's OpModes call. {@link #getInstance()} is null outside the
 * Dashboard's life cycle, as upstream; here it stays null unless a test harness installs a stand-in.
 */
public class FtcDashboard {
    private static FtcDashboard instance;

    /** Upstream the constructor is private; protected here only so that a test harness can stand in. */
    protected FtcDashboard() {
    }

    /** Not upstream: the test harness's stand-in becomes the instance (null removes it). */
    protected static void setInstance(FtcDashboard dashboard) {
        instance = dashboard;
    }

    /** The active instance, or null outside of its life cycle. */
    public static FtcDashboard getInstance() {
        return instance;
    }

    /** Queues a packet; upstream sends the queue every 100 ms (DashboardCore.sendTelemetryPacket). */
    public void sendTelemetryPacket(TelemetryPacket telemetryPacket) {
        telemetryPacket.addTimestamp();
    }
}
