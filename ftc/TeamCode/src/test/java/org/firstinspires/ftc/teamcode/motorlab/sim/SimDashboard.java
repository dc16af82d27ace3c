/* motorlab JVM test: FTC Dashboard's stand-in, printing each telemetry packet as one JSON line. */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.acmerobotics.dashboard.FtcDashboard;
import com.acmerobotics.dashboard.telemetry.TelemetryPacket;
import java.io.PrintStream;
import java.lang.reflect.Field;
import java.util.Locale;
import java.util.Map;

/**
 * Installed as {@link FtcDashboard#getInstance()}: each packet sent is written to {@code out} as the JSON
 * object Dashboard's Gson makes of a TelemetryPacket ({@code {"timestamp":…,"data":{…},"log":[],"field":{…},
 * "fieldOverlay":{…}}}), read from the packet's fields by reflection as Gson does. motorlab's emulated robot
 * (motorlab.robot.emulator_jvm) forwards these lines to its clients in RECEIVE_TELEMETRY batches.
 */
public final class SimDashboard extends FtcDashboard {
    private final PrintStream out;
    public int packets = 0;

    private SimDashboard(PrintStream out) {
        this.out = out;
    }

    /** Make a stand-in writing to {@code out} the Dashboard instance. */
    public static SimDashboard install(PrintStream out) {
        SimDashboard dashboard = new SimDashboard(out);
        setInstance(dashboard);
        return dashboard;
    }

    @Override
    public void sendTelemetryPacket(TelemetryPacket packet) {
        super.sendTelemetryPacket(packet); // the timestamp, as upstream
        StringBuilder json = new StringBuilder("{\"timestamp\":").append(field(packet, "timestamp"));
        json.append(",\"data\":{");
        int k = 0;
        for (Map.Entry<?, ?> e : ((Map<?, ?>) field(packet, "data")).entrySet()) {
            json.append(k++ > 0 ? "," : "").append(RunSim.q(String.valueOf(e.getKey()))).append(':')
                    .append(RunSim.q(String.valueOf(e.getValue())));
        }
        json.append("},\"log\":[],\"field\":{\"ops\":[]},\"fieldOverlay\":{\"ops\":[]}}");
        synchronized (out) {
            out.println(json);
            out.flush();
        }
        packets++;
    }

    private static Object field(Object packet, String name) {
        try {
            Field f = packet.getClass().getDeclaredField(name);
            f.setAccessible(true);
            return f.get(packet);
        } catch (ReflectiveOperationException e) {
            throw new IllegalStateException(String.format(Locale.US, "TelemetryPacket has no field %s", name), e);
        }
    }
}
