// motorlab stub of FTC Dashboard's API (acmerobotics/ftc-dashboard; written from its public signatures, no
// Dashboard code): DashboardCore/src/main/java/com/acmerobotics/dashboard/telemetry/TelemetryPacket.java at
// v0.4.16 and v0.5.0 (lines 44, 54, 89; unchanged from v0.4.10 to v0.6.0 for these three).
// Compile-time only: on a robot the real class is used. See ftc/README.md.
package com.acmerobotics.dashboard.telemetry;

import java.util.SortedMap;
import java.util.TreeMap;

/**
 * Stub of TelemetryPacket: two of the fields Dashboard serialises (with Gson, by reflection) and the
 * methods motorlab uses. Every value is stored as its {@code toString()}: the client receives text.
 */
public class TelemetryPacket {
    private long timestamp;
    private final SortedMap<String, String> data = new TreeMap<String, String>();

    public TelemetryPacket() {
    }

    /** Stores one key and value (as text; null as "null"). */
    public void put(String key, Object value) {
        data.put(key, String.valueOf(value));
    }

    /** Sets the timestamp to now [ms since the epoch]; called when the packet is sent. */
    public long addTimestamp() {
        timestamp = System.currentTimeMillis();
        return timestamp;
    }
}
